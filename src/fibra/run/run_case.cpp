#include "fibra/run/run_case.hpp"

#include "fibra/run/resolve.hpp"

#include <algorithm>
#include <omp.h>

#include <fmt/format.h>

#include <array>
#include <csignal>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <nlohmann/json.hpp>

#include "fibra/core/debug.hpp"
#include "fibra/core/error.hpp"
#include "fibra/core/file.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/io/case_writer.hpp"
#include "fibra/io/output_writer.hpp"
#include "fibra/io/slice.hpp"
#include "fibra/model/fabric.hpp"
#include "fibra/model/fabric_report.hpp"
#include "fibra/model/model.hpp"
#include "fibra/run/curve_plotter.hpp"
#include "fibra/run/resolve.hpp"
#include "fibra/solver/solver_state.hpp"

namespace fibra {

namespace {

/// The subfolders a run of `c` writes into (prepare_output_dir checks those already there):
/// the ParaView series, the states, and the slices and plots of a woven sample's steps.
std::vector<std::string> output_subdirs(const Case& c) {
  std::vector<std::string> dirs = {"fibers", "lines", "state"};
  if (c.contact.enabled) dirs.push_back("contacts");
  if (!c.bodies.empty()) dirs.push_back("bodies");
  if (!c.tows.empty()) dirs.push_back("slices");
  if (c.output.plots && std::any_of(c.steps.begin(), c.steps.end(), [](const StepSpec& st) { return st.is_test(); }))
    dirs.push_back("plots");
  return dirs;
}

/// The case as its run read it: the file's text, or for a case made in code its TOML.
std::pair<std::string, std::string> case_source(const Case& c) {
  std::error_code ec;
  const std::string ext = std::filesystem::path(c.file).extension().string();
  if ((ext == ".toml" || ext == ".json") && std::filesystem::is_regular_file(c.file, ec)) {
    std::ifstream in(c.file, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.good() || in.eof()) return {text, c.file};
  }
  return {write_case_toml(c), "case.toml"};
}

/// The key's step index when it is a step's (`step[2].strain` -> 2), else -1.
int step_of_key(const std::string& key) {
  if (key.rfind("step[", 0) != 0) return -1;
  const size_t end = key.find(']');
  return end == std::string::npos ? -1 : std::atoi(key.substr(5, end - 5).c_str());
}

/// Refuses a checkpoint whose case differs from `c` (its source: case_source) in anything but
/// the steps after the one under way and the checkpoints' rate: the message lists what changed.
void check_case_unchanged(const Case& c, const std::pair<std::string, std::string>& source, const Checkpoint& ck,
                          const std::string& checkpoint_file) {
  const auto& [text, file] = source;
  if (text == ck.case_text) return;
  auto is_json = [](const std::string& f) { return std::filesystem::path(f).extension() == ".json"; };
  const auto before = case_file_keys(ck.case_text, is_json(ck.case_file), ck.case_file);
  const auto now = case_file_keys(text, is_json(file), file);
  std::vector<std::string> changes;
  std::string first;
  auto note = [&](const std::string& key, const std::string& what) {
    if (step_of_key(key) > ck.progress.step || key == "output.checkpoint") return;
    if (first.empty()) first = key;
    if (changes.size() < 6) changes.push_back(fmt::format("`{}` {}", key, what));
  };
  for (const auto& [key, value] : before) {
    const auto it = now.find(key);
    if (it == now.end()) note(key, fmt::format("removed (was {})", value));
    else if (it->second != value) note(key, fmt::format("was {}, is {}", value, it->second));
  }
  for (const auto& [key, value] : now)
    if (!before.count(key)) note(key, fmt::format("added ({})", value));
  if (first.empty()) return;
  std::string list;
  for (const std::string& ch : changes) list += (list.empty() ? "" : "; ") + ch;
  throw InputError(c.file, first,
                   fmt::format("the case changed since the checkpoint it would resume from ({}): {}. A resumed run "
                               "goes on with the case it started with; only the steps after the one under way (step {}, "
                               "\"{}\") may change. Undo the change, or run the case again without --resume",
                               checkpoint_file, list, ck.progress.step + 1, ck.state.step));
}

/// The checkpoint a resumed run goes on from: OUT/state/checkpoint.bin, of this case.
Checkpoint load_checkpoint(const Case& c, const std::pair<std::string, std::string>& source,
                           const std::string& out_dir) {
  const std::string file = (std::filesystem::path(out_dir) / "state" / "checkpoint.bin").string();
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) {
    std::string status;
    try {
      std::ifstream in(std::filesystem::path(out_dir) / "summary.json");
      if (in) status = nlohmann::json::parse(in).value("status", "");
    } catch (const std::exception&) {
    }
    throw InputError(out_dir, "--resume",
                     status == "converged"
                         ? fmt::format("the run in \"{}\" finished (summary.json: converged): nothing to resume", out_dir)
                         : fmt::format("no checkpoint in \"{}\" (state/checkpoint.bin): its run wrote none, or is "
                                       "not a run of fibra; run the case without --resume",
                                       out_dir));
  }
  Checkpoint ck = read_checkpoint_file(file);
  check_case_unchanged(c, source, ck, file);
  return ck;
}

}  // namespace

RunReport run_case(const Case& c, const RunOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (options.threads > 0) omp_set_num_threads(options.threads);
  // [start]: its output directory replaces the states of the run it goes on from: refuse.
  if (!c.start.empty()) {
    std::error_code ec;
    if (std::filesystem::equivalent(options.out_dir, c.start, ec))
      throw InputError(c.file, "start.from",
                       fmt::format("\"{}\" is also this run's output directory (its states would be replaced): "
                                   "give the run another --out directory",
                                   c.start));
  }
  // The case as read (text, file): kept in checkpoints, compared with a resumed run's.
  const std::pair<std::string, std::string> source =
      options.case_text.empty() ? case_source(c) : std::make_pair(options.case_text, options.case_text_file);
  // --resume: the run goes on from the checkpoint in its output directory.
  const std::optional<Checkpoint> resumed =
      options.resume ? std::optional<Checkpoint>(load_checkpoint(c, source, options.out_dir)) : std::nullopt;
  const std::string checkpoint_file =
      (std::filesystem::path(options.out_dir.empty() ? "." : options.out_dir) / "state" / "checkpoint.bin").string();
  // An output directory that cannot be written stops the run before anything is computed.
  prepare_output_dir(options.out_dir, output_subdirs(c));
  ResolvedCase resolved = resolve_case(c);
  const Model& model = resolved.model;
  StaticSolver solver(c, model, std::move(resolved.bodies));
  if (options.progress) solver.set_progress(options.progress);
  if (resumed) {
    check_state_fits(resumed->state, model, solver.bodies() ? solver.bodies()->num_bindings() : 0, checkpoint_file);
    const SolverProgress& p = resumed->progress;
    if (p.step >= static_cast<int>(c.steps.size()) ||
        (!p.detection_memory.empty() && p.detection_memory.size() != model.fibers.size()) ||
        (p.factor.valid && p.factor.bodies.size() != (solver.bodies() ? solver.bodies()->snapshot().size() : 0)))
      throw InputError(checkpoint_file, "(file)", "its progress does not match the case's model: the file is corrupt");
    solver.resume(resumed->state, resumed->progress);
  } else if (resolved.start) {
    // [start]: the run goes on from the state an earlier run saved at the end of its last step.
    solver.restore_state(*resolved.start);
  }
  // What a resumed run's bookkeeping starts from (run_point() of the run that wrote it).
  const nlohmann::json point = resumed ? nlohmann::json::parse(resumed->run) : nlohmann::json{};
  const VecX initial = solver.state();
  std::vector<std::string> columns = solver.reaction_columns();
  const std::vector<std::string> contact_columns = {
      "contact:zones",       "contact:elements",   "contact:max_penetration_ratio", "contact:normal_force",
      "contact:detections",  "contact:normal_updates", "contact:penalty_raises",    "contact:penalty_softenings",
      "contact:detection_time", "contact:solve_time"};
  if (solver.has_contact()) columns.insert(columns.end(), contact_columns.begin(), contact_columns.end());
  const BodySystem* bodies = solver.bodies();
  if (bodies) columns.insert(columns.end(), {"binding:updates", "binding:max_violation"});
  // Steps with a drag (weave, relax, biaxial, shear): the drag stiffness of each increment and
  // the drag force left at its end (0 in other steps).
  const bool dragged = solver.has_contact() && std::any_of(c.steps.begin(), c.steps.end(), [](const StepSpec& st) {
                         return st.kind == StepSpec::Kind::Weave || st.is_proximal();
                       });
  if (dragged) columns.insert(columns.end(), {"relax:drag_residual", "relax:spin_residual", "relax:drag"});
  // Load steps: the stability of each increment's equilibrium (negative pivots of its tangent).
  const bool loaded = std::any_of(c.steps.begin(), c.steps.end(),
                                  [](const StepSpec& st) { return st.kind == StepSpec::Kind::Standard; });
  if (loaded) columns.push_back("stability:negative_pivots");
  // Woven samples: the fabric report (model/fabric_report.hpp) per increment, O(nodes).
  const bool fabric = !c.tows.empty();
  if (fabric) columns.insert(columns.end(), {"fabric:warp_crimp", "fabric:weft_crimp", "fabric:thickness"});
  const std::unique_ptr<OutputWriter> writer_ptr =
      resumed ? std::make_unique<OutputWriter>(options.out_dir, model, columns, c.output.tube_sides, point.at("writer"))
              : std::make_unique<OutputWriter>(options.out_dir, model, columns, c.output.tube_sides);
  OutputWriter& writer = *writer_ptr;
  // The expanded case (a [fabric] as its fibers, bodies and tows): `fibra slice` and any later
  // look at the outputs rebuild the model from it.
  write_file_atomic(writer.dir() + "/case.toml", write_case_toml(c));
  const std::unique_ptr<CurvePlotter> plotter_ptr = resumed
                                                        ? std::make_unique<CurvePlotter>(c, writer.dir(), point.at("plots"))
                                                        : std::make_unique<CurvePlotter>(c, writer.dir());
  CurvePlotter& plotter = *plotter_ptr;
  std::vector<std::string> slice_files;  // relative to the output directory
  std::optional<FabricReport> last_fabric;
  nlohmann::json last_fabric_json;  // to_json(*last_fabric), or a resumed run's
  std::string last_fabric_step;
  nlohmann::json fabric_steps = nlohmann::json::array();
  // Load steps' increments that ended on an unstable equilibrium (negative pivots), and the first.
  nlohmann::json unstable = {{"increments", 0}, {"first", nullptr}};
  double time_fabric = 0.0;
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  double time_output = 0.0;
  // Loading curves of the biaxial and shear steps (curves_<step>.csv): the edge bodies'
  // forces on the fabric and their relative motion since the step's start.
  // The edge bodies' centres and forces at the last increment (their initial state before the
  // first), and their centres at the start of the loading step.
  std::array<Index, 4> edge{};
  bool edges = bodies != nullptr;
  for (int e = 0; e < 4 && edges; ++e) edges = (edge[e] = model.body_index(kEdgeBodies[e])) >= 0;
  std::array<Vec3, 4> centre{}, force{}, start{};
  for (int e = 0; e < 4 && edges; ++e) {
    const BodyState bs = bodies->state(edge[e], initial);
    centre[e] = bs.center;
    force[e] = bs.force;
  }
  int curves_step = -1;
  std::ofstream curves;
  nlohmann::json curves_files = nlohmann::json::array();
  auto curve_row = [&](const std::string& step, int increment, double load, double elements, double penetration) {
    const double lx = start[1].x() - start[0].x(), ly = start[3].y() - start[2].y();
    const double warp_strain = (centre[1].x() - centre[0].x()) / lx - 1.0;
    const double weft_strain = (centre[3].y() - centre[2].y()) / ly - 1.0;
    // The shear angle: the turn of the line between the bottom and top edges' centres, from the
    // offset along x since the start and the height now (the start's with the height held).
    const double offset = (centre[3].x() - centre[2].x()) - (start[3].x() - start[2].x());
    const double angle = std::atan2(offset, centre[3].y() - centre[2].y()) * 180.0 / std::numbers::pi;
    curves << fmt::format("{},{},{},{},{},{},{},{},{},{},{}\n", step, increment, load, warp_strain, weft_strain,
                          force[1].x(), force[3].y(), angle, force[3].x(), elements, penetration);
    curves.flush();
  };
  nlohmann::json states = nlohmann::json::array();  // the state files written at step ends
  // Checkpoints ([output] checkpoint): the latest converged increment's, kept to be written
  // when the run is interrupted; the step's start and the last written one's wall times.
  std::optional<Checkpoint> latest;
  int written_checkpoint = -1;  // total increments of the last checkpoint written
  double checkpoint_time = 0.0, last_checkpoint_wall = 0.0, step_started = 0.0, last_wall = 0.0;
  int checkpoint_step = -1;
  const double wall_offset = resumed ? resumed->progress.wall_time : 0.0;
  auto vec3s_to_json = [](const std::array<Vec3, 4>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (const Vec3& x : v) a.push_back({x.x(), x.y(), x.z()});
    return a;
  };
  auto vec3s_from_json = [](const nlohmann::json& a) {
    std::array<Vec3, 4> v{};
    for (int e = 0; e < 4; ++e)
      for (int k = 0; k < 3; ++k) {
        const nlohmann::json& x = a.at(e).at(k);
        v[e][k] = x.is_null() ? std::nan("") : x.get<double>();  // JSON writes NaN as null
      }
    return v;
  };
  // The bookkeeping a checkpoint holds, for the resumed run's outputs to go on as these do.
  auto run_point = [&]() {
    nlohmann::json r = {{"curves_step", curves_step},
                        {"curves_bytes", curves.is_open() ? static_cast<std::int64_t>(curves.tellp()) : 0},
                        {"start", vec3s_to_json(start)},
                        {"centre", vec3s_to_json(centre)},
                        {"force", vec3s_to_json(force)},
                        {"curves_files", curves_files},
                        {"slices", slice_files},
                        {"fabric_steps", fabric_steps},
                        {"fabric", last_fabric_json},
                        {"fabric_step", last_fabric_step},
                        {"states", states},
                        {"checkpoint_step", checkpoint_step},
                        {"step_started", step_started},
                        {"last_wall", last_wall},
                        {"unstable", unstable}};
    return nlohmann::json{{"writer", writer.resume_point()}, {"plots", plotter.resume_point()}, {"run", r}};
  };
  if (resumed) {
    const nlohmann::json& r = point.at("run");
    curves_step = r.at("curves_step").get<int>();
    start = vec3s_from_json(r.at("start"));
    centre = vec3s_from_json(r.at("centre"));
    force = vec3s_from_json(r.at("force"));
    curves_files = r.at("curves_files");
    slice_files = r.at("slices").get<std::vector<std::string>>();
    fabric_steps = r.at("fabric_steps");
    last_fabric_json = r.at("fabric");
    last_fabric_step = r.at("fabric_step").get<std::string>();
    states = r.at("states");
    checkpoint_step = r.at("checkpoint_step").get<int>();
    step_started = r.at("step_started").get<double>();
    last_wall = r.at("last_wall").get<double>();
    if (r.contains("unstable")) unstable = r.at("unstable");
    written_checkpoint = resumed->progress.total;
    last_checkpoint_wall = wall_offset;
    if (curves_step >= 0) {
      // The curves of the step under way, back to their rows at the checkpoint.
      const std::string name = writer.dir() + "/curves_" + step_file_stem(c.steps[curves_step].name) + ".csv";
      const auto bytes = r.at("curves_bytes").get<std::uintmax_t>();
      std::error_code ec;
      if (std::filesystem::file_size(name, ec) < bytes || ec)
        throw InputError(name, "(file)", fmt::format("shorter than at the checkpoint ({} bytes): the output directory "
                                                     "was changed since; run the case again without --resume",
                                                     bytes));
      std::filesystem::resize_file(name, bytes, ec);
      curves.open(name, std::ios::app);
      if (ec || !curves) throw RunError(fmt::format("cannot open for writing '{}'", name));
    }
  }
  // summary.json exists from the run's start: "running", with the last converged increment,
  // rewritten after each one, so that a run killed by the system says how far it got (the
  // final summary replaces it when the run ends, whatever its status).
  auto running_summary = [&](const IncrementInfo* info) {
    nlohmann::json j;
    j["case"] = c.file;
    j["title"] = c.title;
    j["status"] = "running";
    j["converged"] = false;
    j["progress"] = info ? nlohmann::json{{"step", info->step},
                                          {"step_number", info->step_index + 1},
                                          {"steps", c.steps.size()},
                                          {"increment", info->increment},
                                          {"load_factor", info->load_factor},
                                          {"total_increments", info->total_increments}}
                         : nlohmann::json{{"step", nullptr}, {"step_number", 0}, {"steps", c.steps.size()},
                                          {"increment", 0}, {"load_factor", 0.0}, {"total_increments", 0}};
    j["wall_time"] = wall_offset + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    j["states"] = states;
    writer.write_summary(j);
  };
  // A file of the state/ subfolder (`name` relative to the output directory), the folder made.
  auto state_path = [&](const std::string& name) {
    std::error_code ec;
    std::filesystem::create_directories(writer.dir() + "/state", ec);
    return writer.dir() + "/" + name;
  };
  auto observe = [&](const IncrementInfo& info, const VecX& q) {
    const StepSpec& st = c.steps[info.step_index];
    if (edges && st.is_test() && info.step_index != curves_step) {
      // A new loading step: its curves start from the state at its start.
      curves_step = info.step_index;
      start = centre;
      const std::string name = "curves_" + step_file_stem(info.step) + ".csv";
      if (curves.is_open()) curves.close();
      curves.open(writer.dir() + "/" + name, std::ios::trunc);
      if (!curves) throw RunError(fmt::format("cannot open for writing '{}/{}'", writer.dir(), name));
      curves << "step,increment,load_factor,warp_strain,weft_strain,warp_force,weft_force,shear_angle_deg,"
                "shear_force,contact_elements,max_penetration_ratio\n";
      curve_row(info.step, 0, 0.0, std::nan(""), std::nan(""));
      curves_files.push_back({{"step", info.step},
                              {"kind", StepSpec::kind_name(st.kind)},
                              {"file", name},
                              {"strain", st.strain},
                              {"ratio", st.ratio},
                              {"angle", st.angle}});
    }
    if (edges) {
      for (int e = 0; e < 4; ++e) {
        centre[e] = info.bodies[edge[e]].center;
        force[e] = info.bodies[edge[e]].force;
      }
      if (info.step_index == curves_step && info.settled)
        curve_row(info.step, info.increment, info.load_factor, double(info.contact.elements),
                  info.contact.max_penetration_ratio);
    }
    std::optional<FabricReport> rep;
    if (fabric) {
      const auto tf = std::chrono::steady_clock::now();
      if (solver.has_contact())
        rep = fabric_report(c, model, q, &solver.problem().contacts(), &info.contact_responses);
      else
        rep = fabric_report(c, model, q);
      time_fabric += std::chrono::duration<double>(std::chrono::steady_clock::now() - tf).count();
    }
    const auto t = std::chrono::steady_clock::now();
    HistoryRow row{info.step, info.step_index, info.increment, info.load_factor, info.iterations,
                   info.residual, info.wall_time, info.reactions};
    if (solver.has_contact()) {
      const ContactStats& cs = info.contact;
      row.extra.insert(row.extra.end(),
                       {double(cs.zones), double(cs.elements), cs.max_penetration_ratio, cs.total_normal_force,
                        double(cs.detections), double(cs.normal_updates), double(cs.penalty_raises),
                        double(cs.penalty_softenings), cs.detection_time,
                        info.increment_time - cs.detection_time});
    }
    if (bodies) row.extra.insert(row.extra.end(), {double(info.binding_updates), info.binding_violation});
    if (dragged) row.extra.insert(row.extra.end(), {info.relax_residual, info.spin_residual, info.drag});
    if (loaded) row.extra.push_back(double(info.negative_pivots));
    if (info.negative_pivots > 0) {
      unstable["increments"] = unstable["increments"].get<int>() + 1;
      if (unstable["first"].is_null())
        unstable["first"] = {{"step", info.step},
                             {"increment", info.increment},
                             {"load_factor", info.load_factor},
                             {"negative_pivots", info.negative_pivots}};
    }
    if (rep) row.extra.insert(row.extra.end(), {rep->warp_crimp, rep->weft_crimp, rep->thickness});
    if (rep && info.step_end) {
      const StepSpec::Kind kind = st.kind;
      fabric_steps.push_back({{"step", info.step},
                              {"kind", StepSpec::kind_name(kind)},
                              {"warp_crimp", num(rep->warp_crimp)},
                              {"weft_crimp", num(rep->weft_crimp)},
                              {"thickness", num(rep->thickness)},
                              {"max_penetration", num(rep->max_penetration)},
                              {"max_penetration_ratio", num(rep->max_penetration_ratio)}});
      last_fabric = rep;
      last_fabric_json = to_json(*rep);
      last_fabric_step = info.step;
      if (kind == StepSpec::Kind::Weave || kind == StepSpec::Kind::Relax || st.is_test()) {
        // Default slices across the middle of the sample: x half-way between the two middle
        // weft axes (cuts the warps), y likewise (cuts the wefts).
        const std::string stem = writer.dir() + "/slices/" + step_file_stem(info.step);
        const std::string title = c.title.empty() ? c.name : c.title;
        write_slice(stem + "_x", model, q, c.tows, 0, rep->section_x,
                    fmt::format("{}: step {} ({}), x = {:.4g} mm", title, info.step, StepSpec::kind_name(kind),
                                1e3 * rep->section_x));
        write_slice(stem + "_y", model, q, c.tows, 1, rep->section_y,
                    fmt::format("{}: step {} ({}), y = {:.4g} mm", title, info.step, StepSpec::kind_name(kind),
                                1e3 * rep->section_y));
        for (const char* name : {"_x.svg", "_x.png", "_y.svg", "_y.png"})
          slice_files.push_back("slices/" + step_file_stem(info.step) + name);
      }
    }
    // The state at each step's end, for runs that go on from it ([start] from = this directory),
    // and with FIBRA_DEBUG_CHECKPOINT after every increment.
    auto save = [&](const std::string& name, int steps_done) {
      write_state_file(state_path(name), solver.save_state(info.step, steps_done));
    };
    if (debug_checkpoint())
      save(fmt::format("state/checkpoint_{}_{}.bin", step_file_stem(info.step), info.increment), info.step_index);
    if (info.step_end) {
      const std::string name = "state/" + step_file_stem(info.step) + ".bin";
      save(name, info.step_index + 1);
      states.push_back({{"step", info.step}, {"file", name}});
    }
    // A test level's pseudo-time increments (its drag still pulls) are not states of the
    // fabric: by default only each level's settled state, a point of the curves, is written.
    const bool levels_only = c.output.test_levels && st.is_test() && solver.has_contact() && c.solver.method.relax_drag > 0.0;
    const bool vtu = info.step_end || (levels_only ? info.settled : info.total_increments % c.output.every == 0);
    std::vector<BodyPoint> body_points;
    if (vtu && bodies)
      for (Index b = 0; b < bodies->num_bodies(); ++b) {
        const BodyState& bs = info.bodies[b];
        body_points.push_back({model.bodies[b].name, bs.center, bs.frame, bs.center - model.bodies[b].center,
                               bs.rotation, bs.force, bs.moment, bodies->member_positions(b, q)});
      }
    std::vector<ContactPoint> points;
    if (vtu && solver.has_contact()) {
      const auto& contacts = solver.problem().contacts();
      const std::vector<ContactResponse>& responses = info.contact_responses;
      points.reserve(contacts.size());
      for (size_t k = 0; k < contacts.size(); ++k) {
        const ContactElement& ce = contacts[k];
        const Vec3 xa = particle_position(ce.a, q.data() + model.elements[ce.a.element].first_dof);
        const Vec3 xb = particle_position(ce.b, q.data() + model.elements[ce.b.element].first_dof);
        points.push_back({0.5 * (xa + xb), ce.normal, responses[k].friction, responses[k].gap, responses[k].normal_force,
                          responses[k].slip, ce.zone});
      }
    }
    writer.write_increment(q, row, info.step_index + info.load_factor, vtu, solver.has_contact() ? &points : nullptr,
                           bodies ? &body_points : nullptr);
    time_output += std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    // The plots of a test step once its curves are complete (after its history is written).
    if (info.step_end && info.step_index == curves_step) plotter.plot(curves_step);
    running_summary(&info);
    if (debug_kill_increment() == info.total_increments) std::raise(SIGKILL);  // tests of --resume
    // The checkpoint ([output] checkpoint): kept in memory after every increment (written if
    // the run is interrupted), written when due; always at a step's end.
    if (info.step_index != checkpoint_step) {
      checkpoint_step = info.step_index;
      step_started = last_wall;
    }
    last_wall = info.wall_time;
    if (c.output.checkpoint != OutputSpec::Checkpoint::Never) {
      const auto tc = std::chrono::steady_clock::now();
      const double wall = info.wall_time;
      bool due = info.step_end;
      switch (c.output.checkpoint) {
        case OutputSpec::Checkpoint::Increments:
          due = due || info.total_increments % c.output.checkpoint_increments == 0;
          break;
        case OutputSpec::Checkpoint::Seconds: due = due || wall - last_checkpoint_wall >= c.output.checkpoint_seconds; break;
        case OutputSpec::Checkpoint::Auto:
          // Steps longer than a minute, at no more than 2 % of the run's time.
          due = due || (wall - step_started >= 60.0 && checkpoint_time <= 0.02 * wall);
          break;
        case OutputSpec::Checkpoint::Never: break;
      }
      latest = Checkpoint{solver.save_state(info.step, info.step_end ? info.step_index + 1 : info.step_index),
                          solver.progress(), run_point().dump(), source.first, source.second};
      if (due) {
        write_checkpoint_file(state_path("state/checkpoint.bin"), *latest);
        written_checkpoint = info.total_increments;
        last_checkpoint_wall = wall;
      }
      checkpoint_time += std::chrono::duration<double>(std::chrono::steady_clock::now() - tc).count();
    }
  };
  // A failed write (a full disk, a file in place of a subfolder) stops the run at the
  // increment it happened, named in the error; every file written before it is kept.
  std::string output_failure;
  auto observer = [&](const IncrementInfo& info, const VecX& q) {
    try {
      observe(info, q);
    } catch (const std::exception& e) {
      output_failure = fmt::format("step \"{}\" ({} of {}), increment {} (load factor {:.6g}): writing the outputs "
                                   "failed: {}",
                                   info.step, info.step_index + 1, c.steps.size(), info.increment, info.load_factor,
                                   e.what());
      throw RunError(output_failure + "; the run stops there, the outputs of the increments before it are kept");
    }
    if (options.on_increment) options.on_increment(info);
  };
  // Initial (reference) state as increment 0 in the ParaView collection.
  std::vector<BodyPoint> initial_bodies;
  if (bodies)
    for (Index b = 0; b < bodies->num_bodies(); ++b) {
      const BodyState bs = bodies->state(b, initial);
      initial_bodies.push_back({model.bodies[b].name, bs.center, bs.frame, bs.center - model.bodies[b].center,
                                bs.rotation, bs.force, bs.moment, bodies->member_positions(b, initial)});
    }
  std::vector<double> initial_extra(columns.size(), 0.0);
  // The bodies' columns of the initial row: their state (zero at a fresh start; where the
  // earlier run left them, with their forces, for a case that goes on from it).
  for (const BodyPoint& bp : initial_bodies) {
    const auto first = std::find(columns.begin(), columns.end(), "body:" + bp.name + ":fx");
    if (first == columns.end() || columns.end() - first < 12) continue;
    const Vec3* parts[4] = {&bp.force, &bp.moment, &bp.displacement, &bp.rotation};
    for (int k = 0; k < 4; ++k)
      for (int i = 0; i < 3; ++i) initial_extra[(first - columns.begin()) + 3 * k + i] = (*parts[k])[i];
  }
  if (fabric) {
    const FabricReport rep = fabric_report(c, model, initial);
    const size_t n = initial_extra.size();
    initial_extra[n - 3] = rep.warp_crimp;
    initial_extra[n - 2] = rep.weft_crimp;
    initial_extra[n - 1] = rep.thickness;
  }
  if (!resumed) {
    writer.write_increment(initial, HistoryRow{"initial", -1, 0, 0.0, 0, 0.0, 0.0, initial_extra}, 0.0, true,
                           nullptr, bodies ? &initial_bodies : nullptr);
    running_summary(nullptr);
  } else {
    IncrementInfo at;
    at.step = resumed->state.step;
    at.step_index = resumed->progress.step;
    at.increment = resumed->progress.done;
    at.load_factor = resumed->progress.lambda;
    at.total_increments = resumed->progress.total;
    running_summary(&at);
  }
  RunReport report;
  try {
    report.result = solver.run(observer);
  } catch (const RunError&) {
    if (output_failure.empty()) throw;
    // What it can of the summary: the run's status and where it stopped (the directory may
    // take no more files).
    nlohmann::json j;
    j["case"] = c.file;
    j["title"] = c.title;
    j["status"] = "output_failed";
    j["converged"] = false;
    j["message"] = output_failure;
    try {
      writer.write_summary(j);
    } catch (const RunError&) {
    }
    throw;
  }
  // A finished run has nothing to resume; an interrupted one can go on from its last
  // converged increment.
  if (report.result.status == RunResult::Status::Converged) {
    std::error_code ec;
    std::filesystem::remove(checkpoint_file, ec);
  } else if (report.result.status == RunResult::Status::Interrupted && latest &&
             latest->progress.total > written_checkpoint) {
    write_checkpoint_file(state_path("state/checkpoint.bin"), *latest);
  }
  report.stats = solver.stats();
  report.final_state = solver.state();
  report.fibers = static_cast<Index>(model.fibers.size());
  report.nodes = model.num_nodes();
  report.dofs = model.num_dofs();
  report.elements = static_cast<Index>(model.elements.size());
  report.fabric = last_fabric;
  writer.write_nodes(solver.state());
  plotter.plot(curves_step);  // a run stopped within a test step: the plots of what converged
  report.paraview = {"fibers.pvd", "lines.pvd"};
  if (solver.has_contact()) report.paraview.push_back("contacts.pvd");
  if (bodies && bodies->num_bodies() > 0) report.paraview.push_back("bodies.pvd");
  for (const nlohmann::json& e : curves_files) report.curves.push_back(e["file"].get<std::string>());
  report.plots = plotter.files();
  report.plots_error = plotter.error();
  report.slices = slice_files;
  for (const nlohmann::json& e : states) report.states.push_back(e["file"].get<std::string>());
  report.wall_time = wall_offset + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  report.unstable_increments = unstable["increments"].get<int>();
  if (report.unstable_increments > 0) {
    const nlohmann::json& f = unstable["first"];
    const int pivots = f["negative_pivots"].get<int>();
    report.first_unstable = fmt::format("step \"{}\" at load factor {:.4g} ({} negative pivot{})",
                                        f["step"].get<std::string>(), f["load_factor"].get<double>(), pivots,
                                        pivots == 1 ? "" : "s");
  }

  const SolverStats& s = report.stats;
  nlohmann::json j;
  j["case"] = c.file;
  j["title"] = c.title;
  j["status"] = report.result.status_name();
  j["converged"] = report.result.status == RunResult::Status::Converged;
  j["message"] = report.result.message;
  if (report.result.status != RunResult::Status::Converged)
    j["stopped_at"] = {{"step", report.result.step},
                       {"load_factor", report.result.load_factor},
                       {"attempted_load_factor", report.result.attempted_load_factor},
                       {"residual_history", report.result.residual_history}};
  if (report.result.status == RunResult::Status::Failed) {
    const StallDiagnosis& d = report.result.diagnosis;
    j["diagnosis"] = {{"tangent", d.tangent_name()},
                      {"softest_stiffness", d.softest_stiffness},
                      {"bending_stiffness", d.bending_stiffness},
                      {"softest_mode", d.softest_mode},
                      {"largest_motion", d.largest_motion},
                      {"refusal", d.refusal},
                      {"text", d.text()}};
  }
  j["counts"] = {{"fibers", report.fibers}, {"nodes", report.nodes}, {"dofs", report.dofs},
                 {"elements", report.elements}, {"bodies", model.bodies.size()}, {"bindings", c.bindings.size()}};
  j["timings"] = {{"total", report.wall_time}, {"assembly", s.time_assembly},
                  {"factorization", s.time_factorization}, {"solve", s.time_solve}, {"output", time_output},
                  {"plots", plotter.time()}, {"checkpoints", checkpoint_time}};
  if (fabric) {
    j["timings"]["fabric_report"] = time_fabric;
    if (!last_fabric_json.is_null()) {
      j["fabric"] = last_fabric_json;
      j["fabric"]["step"] = last_fabric_step;
    } else {
      j["fabric"] = nullptr;
    }
    j["fabric_steps"] = fabric_steps;
  }
  if (!curves_files.empty()) {
    j["curves"] = curves_files;
    plotter.add_to_summary(j);
  }
  if (!c.start.empty()) j["start"] = {{"from", c.start}, {"step", c.start_step}, {"file", c.start_state}};
  j["states"] = states;
  if (loaded) j["unstable_equilibria"] = unstable;
  if (resumed)
    j["resumed_from"] = {{"step", resumed->state.step},
                         {"increment", resumed->progress.done},
                         {"total_increments", resumed->progress.total}};
  j["solver"] = {{"linear_solver", c.solver.linear_solver},
                 {"ordering", c.solver.method.ordering},
                 {"threads", omp_get_max_threads()},
                 {"increments", s.increments},
                 {"iterations", s.iterations},
                 {"cuts", s.cuts},
                 {"factorizations", s.factorizations},
                 {"regularized_factorizations", s.regularized_factorizations},
                 {"shifted_iterations", s.shifted_iterations},
                 {"indefinite_iterations", s.indefinite_iterations},
                 {"reused_factorizations", s.reused_factorizations},
                 {"krylov_iterations", s.krylov_iterations},
                 {"line_search_trials", s.line_search_trials},
                 {"searched_solves", s.searched_solves},
                 {"roundoff_convergences", s.roundoff_convergences},
                 {"limited_steps", s.limited_steps},
                 {"binding_updates", s.binding_updates},
                 {"factor_nonzeros", s.factor_nonzeros}};
  writer.write_summary(j);
  return report;
}

}  // namespace fibra
