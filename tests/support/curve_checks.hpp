#pragma once
// Checks of the plots of the loading curves (docs/outputs.md, "Plots"): what a figure's JSON
// sidecar says it shows against curves_STEP.csv, and the PNG header.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace fibra::test {

/// The numeric columns of a curves_STEP.csv by name ("nan" or empty: NaN); `step` is left out.
inline std::map<std::string, std::vector<double>> read_curves_csv(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::string> names;
  std::map<std::string, std::vector<double>> columns;
  auto split = [](const std::string& text) {
    std::vector<std::string> out;
    std::stringstream ss(text);
    for (std::string field; std::getline(ss, field, ',');) out.push_back(field);
    if (!text.empty() && text.back() == ',') out.push_back("");
    return out;
  };
  if (!std::getline(in, line)) {
    ADD_FAILURE() << path << ": empty";
    return columns;
  }
  names = split(line);
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const std::vector<std::string> fields = split(line);
    EXPECT_EQ(fields.size(), names.size()) << path << ": " << line;
    for (size_t k = 0; k < names.size() && k < fields.size(); ++k)
      if (names[k] != "step")  // the one text column
        columns[names[k]].push_back(fields[k].empty() || fields[k] == "nan" ? std::nan("") : std::stod(fields[k]));
  }
  return columns;
}

/// The figure's sidecar STEM.json.
inline nlohmann::json read_sidecar(const std::filesystem::path& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path << " missing";
  std::stringstream ss;
  ss << in.rdbuf();
  return nlohmann::json::parse(ss.str());
}

/// One sidecar series holds exactly the numbers of its source columns (x scaled to its unit;
/// null where the CSV has NaN). `sidecar` is the sidecar's path (sources are relative to it).
inline void expect_series_matches_csv(const nlohmann::json& series, const std::filesystem::path& sidecar) {
  const std::filesystem::path csv = sidecar.parent_path() / series.at("source").get<std::string>();
  const auto columns = read_curves_csv(csv);
  const std::string xc = series.at("x_column"), yc = series.at("y_column");
  ASSERT_TRUE(columns.count(xc) && columns.count(yc)) << csv << ": " << xc << ", " << yc;
  const std::vector<double>& x = columns.at(xc);
  const std::vector<double>& y = columns.at(yc);
  const double xs = series.at("x_scale"), ys = series.at("y_scale");
  ASSERT_EQ(series.at("x").size(), x.size()) << series.at("label") << " vs " << csv;
  ASSERT_EQ(series.at("y").size(), y.size()) << series.at("label") << " vs " << csv;
  for (size_t k = 0; k < x.size(); ++k) {
    if (std::isnan(x[k]))
      EXPECT_TRUE(series["x"][k].is_null()) << k;
    else
      EXPECT_EQ(series["x"][k].get<double>(), xs * x[k]) << series.at("label") << " x[" << k << "]";
    if (std::isnan(y[k]))
      EXPECT_TRUE(series["y"][k].is_null()) << k;
    else
      EXPECT_EQ(series["y"][k].get<double>(), ys * y[k]) << series.at("label") << " y[" << k << "]";
  }
}

/// Width and height of a PNG with a valid signature and an IHDR chunk first and IEND last;
/// {0, 0} otherwise.
inline std::pair<std::uint32_t, std::uint32_t> png_size(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string s = ss.str();
  if (s.size() < 45 || s.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) != 0 || s.compare(12, 4, "IHDR") != 0 ||
      s.compare(s.size() - 8, 4, "IEND") != 0)
    return {0, 0};
  auto be32 = [&](size_t at) {
    std::uint32_t v = 0;
    for (size_t k = 0; k < 4; ++k) v = (v << 8) | static_cast<unsigned char>(s[at + k]);
    return v;
  };
  return {be32(16), be32(20)};
}

}  // namespace fibra::test
