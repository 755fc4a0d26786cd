// fibra._fibra: the compiled core of the Python module `fibra` (python/fibra/). It reads and
// validates cases with the readers the command line uses (a case built from Python dicts goes
// through the JSON reader, so its messages are those of a case file), runs them, draws slices
// and plots and exports results. Everything about results that is plain reading of files
// (CSV, JSON, ParaView) is done in Python with numpy.
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <omp.h>
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "fibra/core/error.hpp"
#include "fibra/core/heap.hpp"
#include "fibra/export/export_options.hpp"
#include "fibra/export/export_result.hpp"
#include "fibra/io/case/schema.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/io/case_writer.hpp"
#include "fibra/io/result_curves.hpp"
#include "fibra/model/model.hpp"
#include "fibra/run/resolve.hpp"
#include "fibra/run/run_case.hpp"
#include "fibra/run/slice_result.hpp"
#include "fibra/solver/blas_threads.hpp"
#include "fibra/solver/static_solver.hpp"

namespace py = pybind11;

namespace {

/// A validated case, shared by the Python objects that hold it.
struct CaseHandle {
  std::shared_ptr<const fibra::Case> c;
  std::string text;  ///< the JSON text of a case built from a dict (empty for a case file)
};

CaseHandle make_handle(fibra::Case c, std::string text = {}) {
  return CaseHandle{std::make_shared<const fibra::Case>(std::move(c)), std::move(text)};
}

/// OpenMP's thread count when the module was loaded: threads = 0 means it (all cores).
int initial_threads = 1;

/// fibra.InputError (a ValueError) with the file and the key path as attributes.
PyObject* input_error_type = nullptr;

// -- runs ------------------------------------------------------------------------------------

std::atomic<bool> interrupted_by_signal{false};

extern "C" void on_sigint(int) {
  interrupted_by_signal.store(true);
  fibra::interrupt_flag().store(true);
}

py::dict increment_dict(const fibra::IncrementInfo& i) {
  py::dict d;
  d["step"] = i.step;
  d["step_index"] = i.step_index;
  d["increment"] = i.increment;
  d["total_increments"] = i.total_increments;
  d["load_factor"] = i.load_factor;
  d["iterations"] = i.iterations;
  d["residual"] = i.residual;
  d["wall_time"] = i.wall_time;
  d["step_end"] = i.step_end;
  d["settled"] = i.settled;
  d["contact_elements"] = i.contact.elements;
  d["negative_pivots"] = i.negative_pivots;
  return d;
}

py::dict report_dict(const fibra::RunReport& r, bool by_signal) {
  py::dict d;
  d["status"] = r.result.status_name();
  d["message"] = r.result.message;
  d["step"] = r.result.step;
  d["load_factor"] = r.result.load_factor;
  d["interrupted_by_signal"] = by_signal;
  d["diagnosis"] = r.result.status == fibra::RunResult::Status::Failed ? r.result.diagnosis.text() : std::string();
  d["residual_history"] = r.result.residual_history;
  d["wall_time"] = r.wall_time;
  py::dict stats;
  stats["increments"] = r.stats.increments;
  stats["iterations"] = r.stats.iterations;
  stats["cuts"] = r.stats.cuts;
  stats["factorizations"] = r.stats.factorizations;
  stats["krylov_iterations"] = r.stats.krylov_iterations;
  stats["indefinite_iterations"] = r.stats.indefinite_iterations;
  d["stats"] = stats;
  py::dict counts;
  counts["fibers"] = r.fibers;
  counts["nodes"] = r.nodes;
  counts["dofs"] = r.dofs;
  counts["elements"] = r.elements;
  d["counts"] = counts;
  d["paraview"] = r.paraview;
  d["curves"] = r.curves;
  d["plots"] = r.plots;
  d["states"] = r.states;
  d["slices"] = r.slices;
  d["plots_error"] = r.plots_error;
  return d;
}

/// Runs a case (run_case) with the GIL released; `on_increment` (may be None) is called with
/// a dict per converged increment and stops the run by returning False. Ctrl-C stops the run
/// at its last converged increment (outputs kept). An exception raised by the callback stops
/// the run likewise and is raised again once the outputs are closed.
py::dict run(const CaseHandle& h, const std::string& out, int threads, bool resume, py::object on_increment) {
  fibra::RunOptions options;
  options.out_dir = out;
  options.threads = threads > 0 ? threads : initial_threads;
  options.resume = resume;
  if (!h.text.empty()) {
    options.case_text = h.text;
    options.case_text_file = "case.json";
  }
  std::optional<py::error_already_set> raised;
  if (!on_increment.is_none()) {
    options.on_increment = [&](const fibra::IncrementInfo& info) {
      py::gil_scoped_acquire gil;
      try {
        const py::object answer = on_increment(increment_dict(info));
        if (!answer.is_none() && !py::bool_(answer)) fibra::interrupt_flag().store(true);
      } catch (py::error_already_set& e) {
        if (!raised) raised.emplace(std::move(e));
        fibra::interrupt_flag().store(true);
      }
    };
  }
  // One run at a time in a process: the stop request (interrupt_flag) and OpenMP's threads are
  // the process's. A second thread's run waits for the first (docs/python.md: run studies in
  // parallel as processes).
  static std::mutex one_run;
  std::unique_lock<std::mutex> lock(one_run, std::defer_lock);
  {
    py::gil_scoped_release release;
    lock.lock();
  }
  fibra::interrupt_flag().store(false);
  interrupted_by_signal.store(false);
  // Python's SIGINT handler only runs between bytecodes, never during the run: fibra's own
  // handler stops it, and Python's is put back after. Only the main thread may set handlers.
  const bool main_thread = PyGILState_Check() && _PyOS_IsMainThread();
  void (*previous)(int) = main_thread ? std::signal(SIGINT, on_sigint) : SIG_ERR;
  if (previous == SIG_IGN) std::signal(SIGINT, SIG_IGN);  // an ignored Ctrl-C stays ignored
  fibra::RunReport report;
  std::exception_ptr failure;
  {
    py::gil_scoped_release release;
    // A single-threaded BLAS, as `fibra` runs (its large factorizations take more threads,
    // set_adaptive_blas_threads), unless the user set OPENBLAS_NUM_THREADS: numpy may have
    // loaded OpenBLAS with a thread per core before fibra/__init__.py could ask for one.
    std::optional<fibra::ScopedBlasThreads> blas;
    if (std::getenv("FIBRA_ADAPTIVE_BLAS_THREADS")) blas.emplace(1);
    try {
      report = fibra::run_case(*h.c, options);
    } catch (...) {
      failure = std::current_exception();
    }
  }
  if (main_thread) std::signal(SIGINT, previous == SIG_ERR ? SIG_DFL : previous);
  fibra::interrupt_flag().store(false);
  omp_set_num_threads(initial_threads);
  if (raised) throw std::move(*raised);
  if (failure) std::rethrow_exception(failure);
  return report_dict(report, interrupted_by_signal.load());
}

py::dict check(const CaseHandle& h) {
  const fibra::ResolvedCase resolved = fibra::resolve_case(*h.c);
  py::dict d;
  d["materials"] = h.c->materials.size();
  d["fibers"] = h.c->fibers.size();
  d["nodes"] = resolved.model.num_nodes();
  d["dofs"] = resolved.model.num_dofs();
  d["steps"] = h.c->steps.size();
  d["tows"] = h.c->tows.size();
  d["bodies"] = resolved.model.bodies.size();
  return d;
}

py::list step_list(const CaseHandle& h) {
  py::list steps;
  for (const fibra::StepSpec& s : h.c->steps) {
    py::dict d;
    d["name"] = s.name;
    d["kind"] = fibra::StepSpec::kind_name(s.kind);
    d["increments"] = s.increments;
    steps.append(d);
  }
  return steps;
}

py::dict export_result(const std::string& dir, const std::string& out, const std::vector<std::string>& voxels,
                       const std::vector<std::string>& voxel_size, const std::vector<std::string>& box,
                       const std::vector<std::string>& samples) {
  const fibra::ExportOptions options = fibra::parse_export_options(out, voxels, voxel_size, box, samples);
  fibra::ExportReport r;
  {
    py::gil_scoped_release release;
    r = fibra::export_result(dir, options);
  }
  py::dict d;
  d["files"] = r.files;
  d["notes"] = r.notes;
  d["tows"] = r.tows;
  d["voxels"] = std::vector<fibra::Index>{r.grid.count[0], r.grid.count[1], r.grid.count[2]};
  d["voxel_size"] = std::vector<double>{r.grid.spacing.x(), r.grid.spacing.y(), r.grid.spacing.z()};
  d["largest_inset"] = r.largest_inset;
  d["fiber_volume_fraction"] = r.fiber_volume_fraction;
  return d;
}

py::dict plot(const std::vector<std::string>& dirs, const std::string& out) {
  const fibra::CurveOverlay overlay = fibra::overlay_curves(dirs, out);
  std::vector<std::string> files;
  {
    py::gil_scoped_release release;
    files = fibra::draw_curve_overlay(overlay);
  }
  py::dict d;
  d["files"] = files;
  d["notes"] = overlay.notes;
  return d;
}

py::dict slice(const std::string& dir, const std::vector<std::string>& planes, std::optional<std::string> tow,
               std::optional<std::string> stations, const std::string& out) {
  fibra::SliceRequest request;
  request.planes = planes;
  request.has_tow = tow.has_value();
  request.has_stations = stations.has_value();
  request.tow = tow.value_or("");
  request.stations = stations.value_or("");
  request.out = out;
  fibra::SliceOutcome outcome;
  {
    py::gil_scoped_release release;
    outcome = fibra::slice_result(dir, request);
  }
  py::dict d;
  d["lines"] = outcome.lines;
  d["files"] = outcome.files;
  return d;
}

/// The schema of case files (io/case/schema.hpp): {table: [key dicts]}.
py::dict schema() {
  py::dict tables;
  for (const fibra::case_file::SectionSpec& section : fibra::case_file::case_schema()) {
    py::list keys;
    for (const fibra::case_file::KeySpec& k : section.keys) {
      py::dict d;
      d["name"] = std::string(k.name);
      d["type"] = std::string(k.type);
      d["default"] = std::string(k.default_value);
      d["allowed"] = std::string(k.allowed);
      d["unit"] = std::string(k.unit);
      d["meaning"] = std::string(k.meaning);
      d["variant"] = std::string(k.variant);
      d["expected"] = std::string(k.expected);
      std::vector<std::string> choices(k.choices.begin(), k.choices.end());
      d["choices"] = choices;
      keys.append(d);
    }
    tables[py::str(std::string(section.name))] = keys;
  }
  return tables;
}

}  // namespace

PYBIND11_MODULE(_fibra, m) {
  m.doc() = "fibra's compiled core; use the package `fibra`";
  // As the command line sets them up (apps/fibra/main.cpp); fibra/__init__.py sets the
  // environment variables libgomp and OpenBLAS read when they load.
  if (std::getenv("FIBRA_ADAPTIVE_BLAS_THREADS")) fibra::set_adaptive_blas_threads(true);
  fibra::keep_freed_memory();
  initial_threads = omp_get_max_threads();

  input_error_type = PyErr_NewExceptionWithDoc(
      "fibra.InputError",
      "Bad input: a case, an option or a result directory that cannot be used. `file` names the "
      "file (or <dict> for a case built in Python), `key` the key path or option, and the message "
      "says what was expected.",
      PyExc_ValueError, nullptr);
  m.add_object("InputError", py::handle(input_error_type));
  py::register_exception<fibra::RunError>(m, "RunError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const fibra::InputError& e) {
      py::object error = py::reinterpret_borrow<py::object>(input_error_type)(e.what());
      error.attr("file") = e.file();
      error.attr("key") = e.key();
      PyErr_SetObject(input_error_type, error.ptr());
    }
  });

  py::class_<CaseHandle>(m, "CaseHandle")
      .def_property_readonly("name", [](const CaseHandle& h) { return h.c->name; })
      .def_property_readonly("title", [](const CaseHandle& h) { return h.c->title; })
      .def_property_readonly("file", [](const CaseHandle& h) { return h.c->file; })
      .def_property_readonly("steps", &step_list)
      .def_property_readonly("tows",
                             [](const CaseHandle& h) {
                               std::vector<std::string> names;
                               for (const fibra::TowSpec& t : h.c->tows) names.push_back(t.name);
                               return names;
                             })
      .def_property_readonly("fibers",
                             [](const CaseHandle& h) {
                               std::vector<std::string> names;
                               for (const fibra::FiberSpec& f : h.c->fibers) names.push_back(f.name);
                               return names;
                             })
      .def("expanded_toml", [](const CaseHandle& h) { return fibra::write_case_toml(*h.c); })
      .def("check", &check);

  m.def(
      "read_case", [](const std::string& path) { return make_handle(fibra::read_case(path)); }, py::arg("path"));
  m.def(
      "parse_case",
      [](const std::string& text, bool json, const std::string& label, const std::string& name) {
        fibra::Case c = json ? fibra::parse_case_json(text, label) : fibra::parse_case_toml(text, label);
        if (!name.empty()) c.name = name;
        return make_handle(std::move(c), json ? text : std::string());
      },
      py::arg("text"), py::arg("json"), py::arg("label"), py::arg("name") = "");
  m.def("schema", &schema);
  m.def("run", &run, py::arg("case"), py::arg("out"), py::arg("threads") = 0, py::arg("resume") = false,
        py::arg("on_increment") = py::none());
  m.def("slice", &slice, py::arg("dir"), py::arg("planes"), py::arg("tow") = py::none(),
        py::arg("stations") = py::none(), py::arg("out") = "");
  m.def("plot", &plot, py::arg("dirs"), py::arg("out") = "");
  m.def("export_result", &export_result, py::arg("dir"), py::arg("out"), py::arg("voxels"), py::arg("voxel_size"),
        py::arg("box"), py::arg("samples"));
}
