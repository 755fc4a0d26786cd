// fibra: command-line program. Parses arguments, validates the case, runs it, reports;
// writes the generated assembly of a case (generate), slices of a run's result (slice),
// plots of the loading curves of one or several runs (plot) and the export of a run's woven
// state to composite models (export).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <optional>

#include "fibra/body/bodies.hpp"
#include "fibra/core/error.hpp"
#include "fibra/core/heap.hpp"
#include "fibra/export/export_result.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/io/case_writer.hpp"
#include "fibra/io/curve_plots.hpp"
#include "fibra/io/nodes_csv.hpp"
#include "fibra/io/output_writer.hpp"
#include "fibra/io/result_curves.hpp"
#include "fibra/io/slice.hpp"
#include "fibra/model/fabric_report.hpp"
#include "fibra/model/model.hpp"
#include "fibra/run/resolve.hpp"
#include "fibra/run/run_case.hpp"
#include "fibra/run/slice_result.hpp"
#include "fibra/solver/blas_threads.hpp"
#include "fibra/solver/static_solver.hpp"

namespace {

void on_interrupt(int) { fibra::interrupt_flag().store(true); }

bool interactive() { return isatty(STDERR_FILENO) && std::getenv("CI") == nullptr; }

int check(const std::string& path) {
  const fibra::Case c = fibra::read_case(path);
  const fibra::ResolvedCase resolved = fibra::resolve_case(c);  // every reference and input error
  const fibra::Model& model = resolved.model;
  fmt::print("{}: valid: {} materials, {} fibers, {} nodes, {} dofs, {} steps\n", path, c.materials.size(),
             c.fibers.size(), model.num_nodes(), model.num_dofs(), c.steps.size());
  return 0;
}

/// "a, b, c" of a list of file names.
std::string join_names(const std::vector<std::string>& names) { return fmt::format("{}", fmt::join(names, ", ")); }

/// Where a run's results are, as one short list: the ParaView views, the curves and their
/// plots (PNG and SVG; the JSON sidecars are for scripts), the slices, the rest.
void print_results(const std::string& out, const fibra::RunReport& r) {
  fmt::print("results in {}/:\n", out);
  fmt::print("  ParaView  {}\n", join_names(r.paraview));
  if (!r.curves.empty()) fmt::print("  curves    {}\n", join_names(r.curves));
  std::vector<std::string> figures;
  for (const std::string& f : r.plots)
    if (!f.ends_with(".json")) figures.push_back(f);
  if (!figures.empty()) fmt::print("  plots     {}\n", join_names(figures));
  if (!r.slices.empty()) fmt::print("  slices    {}/ ({} files)\n", "slices", r.slices.size());
  if (!r.states.empty())
    fmt::print("  states    {} (a case goes on from them with [start] from = \"{}\")\n", join_names(r.states),
               std::filesystem::absolute(out).lexically_normal().string());
  fmt::print("  also      history.csv, nodes.csv, summary.json, case.toml\n");
}

int run(const std::string& path, std::string out, int threads, bool progress_lines, bool resume) {
  const fibra::Case c = fibra::read_case(path);
  if (out.empty()) out = (std::filesystem::path("out") / c.name).string();
  fibra::RunOptions options;
  options.out_dir = out;
  options.threads = threads;
  options.resume = resume;
  const bool tty = interactive();
  // On a terminal one progress line updated in place; with --progress one line per increment
  // (for logs of long runs).
  if (progress_lines)
    options.progress = [](const std::string& line) {
      fmt::print(stderr, "{}\n", line);
      std::fflush(stderr);
    };
  else if (tty)
    options.progress = [](const std::string& line) { fmt::print(stderr, "\r\033[K{}", line); };
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  const fibra::RunReport r = fibra::run_case(c, options);
  if (tty && !progress_lines) fmt::print(stderr, "\n");
  // Missing plots never fail a run: one warning, the curves are there.
  if (!r.plots_error.empty()) fmt::print(stderr, "warning: no plots of the curves: {}\n", r.plots_error);
  const auto& s = r.stats;
  if (r.unstable_increments > 0)
    fmt::print(stderr,
               "note: {} increment{} ended on an unstable equilibrium, the first in {}: a load step follows "
               "its equilibrium path past a bifurcation (history.csv, stability:negative_pivots)\n",
               r.unstable_increments, r.unstable_increments == 1 ? "" : "s", r.first_unstable);
  if (r.result.status == fibra::RunResult::Status::Converged) {
    fmt::print("{}: converged: {} increments, {} Newton iterations, {:.2f} s ({} nodes, {} dofs)\n", path,
               s.increments, s.iterations, r.wall_time, r.nodes, r.dofs);
    print_results(out, r);
    return 0;
  }
  fmt::print(stderr, "{}: {}: {}\n", path, r.result.status_name(), r.result.message);
  if (!r.result.residual_history.empty()) {
    fmt::print(stderr, "  residual history of the last attempt:");
    for (double v : r.result.residual_history) fmt::print(stderr, " {:.3e}", v);
    fmt::print(stderr, "\n");
  }
  if (r.result.status == fibra::RunResult::Status::Failed && r.result.diagnosis.made)
    fmt::print(stderr, "  diagnosis: {}\n", r.result.diagnosis.text());
  fmt::print(stderr, "outputs of every converged increment kept in {}/ (see summary.json)\n", out);
  print_results(out, r);
  return r.result.status == fibra::RunResult::Status::Interrupted ? 130 : 1;
}

namespace fs = std::filesystem;

int generate(const std::string& path, std::string out) {
  const fibra::Case c = fibra::read_case(path);
  const std::string stem = fs::path(path).stem().string();
  if (out.empty()) out = stem + "_generated";
  // Resolved as `check` and `run` resolve it (every reference, the bindings); its bodies give
  // the members' positions for bodies.pvd.
  const fibra::ResolvedCase resolved = fibra::resolve_case(c);
  const fibra::Model& model = resolved.model;
  const std::optional<fibra::BodySystem> body_system =
      model.bodies.empty() ? std::nullopt : std::make_optional<fibra::BodySystem>(c, model);
  const fibra::BodySystem* bodies = body_system ? &*body_system : nullptr;

  std::vector<std::string> files;
  {
    // The ParaView views of the starting assembly (the writer creates the directory).
    fibra::OutputWriter writer(out, model, {}, c.output.tube_sides);
    std::vector<fibra::BodyPoint> points;
    if (bodies)
      for (fibra::Index b = 0; b < bodies->num_bodies(); ++b)
        points.push_back({model.bodies[b].name, model.bodies[b].center, model.bodies[b].axes, fibra::Vec3::Zero(),
                          fibra::Vec3::Zero(), fibra::Vec3::Zero(), fibra::Vec3::Zero(),
                          bodies->member_positions(b, model.reference)});
    writer.write_increment(model.reference, fibra::HistoryRow{"initial", -1, 0, 0.0, 0, 0.0, 0.0, {}}, 0.0, true,
                           nullptr, bodies ? &points : nullptr);
  }
  std::error_code ec;
  fs::remove(fs::path(out) / "history.csv", ec);  // no history: nothing was run
  files.push_back("fibers.pvd");
  files.push_back("lines.pvd");
  if (bodies) files.push_back("bodies.pvd");

  // The case file: the generated assembly as plain fibers, bodies, bindings, tows, weave.
  const fs::path case_file = fs::path(out) / (stem + ".toml");
  {
    const std::string text = fibra::write_case_toml(c);
    std::ofstream f(case_file, std::ios::binary);
    f << text;
    f.close();
    if (!f) throw fibra::RunError(fmt::format("cannot write '{}'", case_file.string()));
  }
  files.insert(files.begin(), case_file.filename().string());

  // A slice across the middle of the sample in x and in y: with tows, where the run draws its
  // slices (half-way between the two middle tow axes of the other direction, see
  // fibra::fabric_report), else the middle of the fibers' bounding box.
  const Eigen::AlignedBox3d box = fibra::centroid_bounds(model, model.reference);
  double middle[2] = {box.center().x(), box.center().y()};
  bool has[2] = {false, false};  // warp, weft tows
  for (const fibra::TowSpec& t : c.tows) has[t.direction == fibra::TowSpec::Direction::Warp ? 0 : 1] = true;
  if (has[0] || has[1]) {
    const fibra::FabricReport rep = fibra::fabric_report(c, model, model.reference);
    if (has[1] && std::isfinite(rep.section_x)) middle[0] = rep.section_x;  // between weft axes
    if (has[0] && std::isfinite(rep.section_y)) middle[1] = rep.section_y;  // between warp axes
  }
  const std::string title = c.title.empty() ? stem + " (generated)" : c.title;
  for (int axis = 0; axis < 2; ++axis) {
    const double value = std::abs(middle[axis]) < 1e-12 * model.length_scale ? 0.0 : middle[axis];  // no 1e-19
    const std::vector<fibra::SliceCut> cuts = fibra::slice_cuts(model, model.reference, c.tows, axis, value);
    if (cuts.empty()) {
      fmt::print("note: the plane {} = {:.6g} mm cuts no fiber: no slice written\n", fibra::slice_axis_name(axis),
                 1e3 * value);
      continue;
    }
    const std::string s = (fs::path(out) / "slices" / fmt::format("slice_{}", fibra::slice_axis_name(axis))).string();
    fibra::write_slice(s, cuts, c.tows, axis, value, title);
    const std::string rel = fs::path(s).lexically_relative(out).string();
    files.push_back(rel + ".svg");
    files.push_back(fmt::format("{}.png ({} = {:.6g} mm)", rel, fibra::slice_axis_name(axis), 1e3 * value));
  }
  fmt::print("{}: generated: {} fibers, {} nodes, {} dofs, {} bodies, {} tows\n", path, model.fibers.size(),
             model.num_nodes(), model.num_dofs(), model.bodies.size(), c.tows.size());
  fmt::print("files in {}/: {}\n", out, fmt::join(files, ", "));
  return 0;
}

/// `fibra plot`: the curves of one or several runs, one figure per step name, overlaid.
int plot(const std::vector<std::string>& dirs, const std::string& out) {
  const fibra::CurveOverlay overlay = fibra::overlay_curves(dirs, out);
  for (const std::string& note : overlay.notes) fmt::print("note: {}\n", note);
  fibra::draw_curve_overlay(overlay);
  for (const fibra::CurveFigure& f : overlay.figures)
    fmt::print("step {} ({}, {} run{}): {}.png, {}.svg, {}.json\n", f.step, f.kind, f.runs.size(),
               f.runs.size() == 1 ? "" : "s", f.stem, f.stem, f.stem);
  return 0;
}

/// The words given to the options of `fibra export` (each empty when absent).
struct ExportWords {
  std::string out;
  std::vector<std::string> voxels, voxel_size, box, samples;
};

/// `fibra export`: tow envelopes, voxel model and Abaqus input of a run's final state.
int export_state(const std::string& dir, const ExportWords& w) {
  const fibra::ExportOptions options = fibra::parse_export_options(w.out, w.voxels, w.voxel_size, w.box, w.samples);
  const fibra::ExportReport r = fibra::export_result(dir, options);
  for (const std::string& note : r.notes) fmt::print("note: {}\n", note);
  const fibra::VoxelGrid& g = r.grid;
  fmt::print("{}: exported {} tows (contours moved inward by up to {:.3g} m where tows touch); {} x {} x {} voxels "
             "of {:.4g} x {:.4g} x {:.4g} m, fiber volume fraction {:.4f}\n",
             dir, r.tows, r.largest_inset, g.count[0], g.count[1], g.count[2], g.spacing.x(), g.spacing.y(),
             g.spacing.z(), r.fiber_volume_fraction);
  std::vector<std::string> shown;
  size_t stl = 0;
  for (const std::string& f : r.files)
    if (f.ends_with(".stl")) ++stl;
    else shown.push_back(f);
  fmt::print("files in {}/: {}, envelopes/ ({} .stl)\n", options.out, fmt::join(shown, ", "), stl);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // OpenMP threads that spin after a parallel region starve CHOLMOD's BLAS threads on small
  // machines; libgomp reads its wait policy at load time, so set it and start again. OpenBLAS's
  // own threads spin (sched_yield) between the many small BLAS calls of a supernodal
  // factorization and take the cores from fibra's OpenMP threads: a single-threaded BLAS is
  // twice as fast on the 2-core machine (docs/performance.md); only the factorizations and
  // solves of large factors then take as many BLAS threads as OpenMP has (they gain 1.4 times
  // on a 480-fiber woven sample). Both stay as the user sets them.
  const bool wait_policy = std::getenv("OMP_WAIT_POLICY") != nullptr;
  const bool blas_threads = std::getenv("OPENBLAS_NUM_THREADS") != nullptr;
  if (!wait_policy || !blas_threads) {
    if (!wait_policy) setenv("OMP_WAIT_POLICY", "passive", 1);
    if (!blas_threads) {
      setenv("OPENBLAS_NUM_THREADS", "1", 1);
      setenv("FIBRA_ADAPTIVE_BLAS_THREADS", "1", 1);  // fibra chose the BLAS threads, not the user
    }
    execv("/proc/self/exe", argv);
  }
  if (std::getenv("FIBRA_ADAPTIVE_BLAS_THREADS")) fibra::set_adaptive_blas_threads(true);
  fibra::keep_freed_memory();  // large freed blocks stay in the heap (fibra/core/heap.hpp)
  CLI::App app{"fibra: woven fabrics and fiber assemblies simulated at the scale of their fibers"};
  app.require_subcommand(1);
  std::string case_path, out;
  int threads = 0;
  auto* run_cmd = app.add_subcommand("run", "run a case file (TOML or JSON)");
  run_cmd->add_option("case", case_path, "case file")->required();
  run_cmd->add_option("--out", out, "output directory (default out/<case name>)");
  run_cmd->add_option("--threads", threads, "OpenMP threads (default: all cores)")->check(CLI::NonNegativeNumber);
  bool progress_lines = false;
  run_cmd->add_flag("--progress", progress_lines,
                    "print one line per converged increment on stderr (default: one line updated in place, on a terminal only)");
  bool resume = false;
  run_cmd->add_flag("--resume", resume,
                    "go on from the checkpoint in the --out directory (state/checkpoint.bin) of a run that was stopped; "
                    "the outputs are those of a run never stopped");
  auto* check_cmd = app.add_subcommand("check", "validate a case file without running it");
  check_cmd->add_option("case", case_path, "case file")->required();
  auto* generate_cmd = app.add_subcommand(
      "generate", "write the assembly a case generates (a [fabric] expanded) as a plain case file, with its "
                  "ParaView views and slices");
  generate_cmd->add_option("case", case_path, "case file")->required();
  generate_cmd->add_option("--out", out, "output directory (default <case file stem>_generated)");
  std::string result_dir;
  fibra::SliceRequest slice_request;
  auto* slice_cmd = app.add_subcommand(
      "slice", "draw the cut of a run's final state by planes, or the slices of one tow along it (SVG and PNG)");
  slice_cmd->add_option("result", result_dir, "output directory of `fibra run` (holds case.toml and nodes.csv)")
      ->required();
  slice_cmd->add_option("--plane", slice_request.planes, "a plane AXIS=VALUE, e.g. x=0.5e-3 (metres; repeat for several)")
      ->allow_extra_args(false);
  auto* tow_option = slice_cmd->add_option("--tow", slice_request.tow,
                                          "a tow's name: slices across it at successive stations (with --stations)");
  auto* stations_option = slice_cmd->add_option(
      "--stations", slice_request.stations, "the number of slices across the --tow, evenly spaced between its ends (1 to 999)");
  slice_cmd->add_option("--out", slice_request.out,
                        "file stem (default RESULT/slices/slice_<axis>_<value>, or RESULT/slices/tow_<name> "
                        "followed by _01, _02, ...)");
  std::vector<std::string> plot_dirs;
  auto* plot_cmd = app.add_subcommand(
      "plot", "draw the loading curves of biaxial and shear steps (PNG, SVG, JSON), several runs overlaid");
  plot_cmd->add_option("results", plot_dirs, "output directories of `fibra run` (hold summary.json and curves_*.csv)")
      ->required();
  plot_cmd->add_option("--out", out, "directory of the figures (default RESULT/plots for one result; required for several)");
  ExportWords export_words;
  auto* export_cmd = app.add_subcommand(
      "export", "write a run's final state for composite models: tow envelopes (STL, VTP), a voxel model (VTI) "
                "and an Abaqus input file (INP)");
  export_cmd->add_option("result", result_dir, "output directory of `fibra run` (holds case.toml and nodes.csv)")
      ->required();
  export_cmd->add_option("--out", export_words.out, "directory of the exported files (required)");
  export_cmd->add_option("--voxels", export_words.voxels, "voxels along x, y and z: NX NY NZ")->expected(1, 3);
  export_cmd->add_option("--voxel-size", export_words.voxel_size, "voxel edge H in metres (instead of --voxels)")
      ->expected(1);
  export_cmd->add_option("--box", export_words.box,
                         "the box to voxelize, XMIN YMIN ZMIN XMAX YMAX ZMAX in metres (default: the fibers' box)")
      ->expected(1, 6);
  export_cmd
      ->add_option("--samples", export_words.samples,
                   "K: K^3 points per voxel for the fiber volume fraction (default 4)")
      ->expected(1);
  CLI11_PARSE(app, argc, argv);
  try {
    if (*run_cmd) return run(case_path, out, threads, progress_lines, resume);
    if (*generate_cmd) return generate(case_path, out);
    if (*slice_cmd) {
      slice_request.has_tow = tow_option->count() > 0;
      slice_request.has_stations = stations_option->count() > 0;
      const fibra::SliceOutcome outcome = fibra::slice_result(result_dir, slice_request);
      for (const std::string& line : outcome.lines) fmt::print("{}\n", line);
      return 0;
    }
    if (*plot_cmd) return plot(plot_dirs, out);
    if (*export_cmd) return export_state(result_dir, export_words);
    return check(case_path);
  } catch (const fibra::InputError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 3;
  }
}
