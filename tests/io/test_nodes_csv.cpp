/// Tests of nodes.csv (io/nodes_csv.hpp): the file OutputWriter::write_nodes writes reads back
/// into the identical state; the reader's errors name the file and the line.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/io/nodes_csv.hpp"
#include "fibra/io/output_writer.hpp"
#include "fibra/model/model.hpp"
#include "support/scratch_dir.hpp"
#include "support/straight_fibers.hpp"

namespace fibra {
namespace {

using test::slurp;

const std::string kStraight = test::straight_fibers_with_quoted_name();

class NodesCsv : public test::ScratchDirTest {
 protected:
  NodesCsv() : ScratchDirTest("fibra_nodes_csv_") {}
};

TEST_F(NodesCsv, ReadsBackIntoTheState) {
  const Case c = parse_case_toml(kStraight, "straight.toml");
  const Model model = build_model(c);
  VecX q = model.reference;
  for (Index k = 0; k < model.num_nodes(); ++k) {
    q[9 * k + 1] += 1e-5 * std::sin(0.7 * k) + 1.0 / 3.0e5;
    q[9 * k + 5] += 0.01 * k;
  }
  {
    OutputWriter writer((m_dir / "run").string(), model, {}, 8);
    writer.write_nodes(q);
  }
  const std::string path = (m_dir / "run" / "nodes.csv").string();
  const VecX back = read_nodes_csv(path, model);
  ASSERT_EQ(back.size(), q.size());
  EXPECT_EQ(back, q);  // full precision
  EXPECT_NE(slurp(path).find("\n\"with, comma\",2,"), std::string::npos);

  // Errors name the file and the line.
  const std::string text = slurp(path);
  auto expect_error = [&](const std::string& bad, const std::string& what) {
    std::ofstream((m_dir / "bad.csv").string()) << bad;
    try {
      read_nodes_csv((m_dir / "bad.csv").string(), model);
      ADD_FAILURE() << "no error for " << what;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.csv"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect_error(text.substr(0, text.rfind('\n', text.size() - 2) + 1), "fiber \"with, comma\" has 2 of its 3 nodes");
  expect_error("fiber,node,x\n", "expected the header");
  std::string unknown = text;
  unknown.replace(unknown.find("\na1,"), 4, "\nzz,");
  expect_error(unknown, "no fiber named \"zz\"");
  const size_t x_column = text.find("\na1,0,") + 6;
  const std::string number = text.substr(0, x_column) + "x" + text.substr(x_column);
  expect_error(number, "column x: expected a finite number");
  try {
    read_nodes_csv((m_dir / "missing.csv").string(), model);
    ADD_FAILURE() << "no error for a missing file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.csv"), std::string::npos);
  }
}

}  // namespace
}  // namespace fibra
