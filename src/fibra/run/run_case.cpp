#include "fibra/run/run_case.hpp"

#include <omp.h>

#include <chrono>
#include <nlohmann/json.hpp>

#include "fibra/io/output_writer.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

RunReport run_case(const Case& c, const RunOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (options.threads > 0) omp_set_num_threads(options.threads);
  const Model model = build_model(c);
  StaticSolver solver(c, model);
  if (options.progress) solver.set_progress(options.progress);
  std::vector<std::string> columns = solver.reaction_columns();
  const std::vector<std::string> contact_columns = {
      "contact:zones",       "contact:elements",   "contact:max_penetration_ratio", "contact:normal_force",
      "contact:detections",  "contact:normal_updates", "contact:penalty_raises",    "contact:detection_time",
      "contact:solve_time"};
  if (solver.has_contact()) columns.insert(columns.end(), contact_columns.begin(), contact_columns.end());
  const BodySystem* bodies = solver.bodies();
  if (bodies) columns.insert(columns.end(), {"binding:updates", "binding:max_violation"});
  OutputWriter writer(options.out_dir, model, columns, c.output.tube_sides);
  double time_output = 0.0;
  auto observer = [&](const IncrementInfo& info, const VecX& q) {
    const auto t = std::chrono::steady_clock::now();
    HistoryRow row{info.step, info.step_index, info.increment, info.load_factor, info.iterations,
                   info.residual, info.wall_time, info.reactions};
    if (solver.has_contact()) {
      const ContactStats& cs = info.contact;
      row.extra.insert(row.extra.end(),
                       {double(cs.zones), double(cs.elements), cs.max_penetration_ratio, cs.total_normal_force,
                        double(cs.detections), double(cs.normal_updates), double(cs.penalty_raises), cs.detection_time,
                        info.increment_time - cs.detection_time});
    }
    if (bodies) row.extra.insert(row.extra.end(), {double(info.binding_updates), info.binding_violation});
    const bool vtu = info.step_end || info.total_increments % c.output.every == 0;
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
  };
  // Initial (reference) state as increment 0 in the ParaView collection.
  std::vector<BodyPoint> initial_bodies;
  if (bodies)
    for (Index b = 0; b < bodies->num_bodies(); ++b)
      initial_bodies.push_back({model.bodies[b].name, model.bodies[b].center, model.bodies[b].axes, Vec3::Zero(),
                                Vec3::Zero(), Vec3::Zero(), Vec3::Zero(),
                                bodies->member_positions(b, model.reference)});
  writer.write_increment(model.reference, HistoryRow{"initial", -1, 0, 0.0, 0, 0.0, 0.0,
                                                     std::vector<double>(columns.size(), 0.0)},
                         0.0, true, nullptr, bodies ? &initial_bodies : nullptr);
  RunReport report;
  report.result = solver.run(observer);
  report.stats = solver.stats();
  report.final_state = solver.state();
  report.fibers = static_cast<Index>(model.fibers.size());
  report.nodes = model.num_nodes();
  report.dofs = model.num_dofs();
  report.elements = static_cast<Index>(model.elements.size());
  writer.write_nodes(solver.state());
  report.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

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
  j["counts"] = {{"fibers", report.fibers}, {"nodes", report.nodes}, {"dofs", report.dofs},
                 {"elements", report.elements}, {"bodies", model.bodies.size()}, {"bindings", c.bindings.size()}};
  j["timings"] = {{"total", report.wall_time}, {"assembly", s.time_assembly},
                  {"factorization", s.time_factorization}, {"solve", s.time_solve}, {"output", time_output}};
  j["solver"] = {{"linear_solver", c.solver.linear_solver},
                 {"ordering", c.solver.ordering},
                 {"threads", omp_get_max_threads()},
                 {"increments", s.increments},
                 {"iterations", s.iterations},
                 {"cuts", s.cuts},
                 {"factorizations", s.factorizations},
                 {"regularized_factorizations", s.regularized_factorizations},
                 {"line_search_trials", s.line_search_trials},
                 {"roundoff_convergences", s.roundoff_convergences},
                 {"binding_updates", s.binding_updates},
                 {"factor_nonzeros", s.factor_nonzeros}};
  writer.write_summary(j);
  return report;
}

}  // namespace fibra
