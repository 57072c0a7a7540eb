// pneumo._core: the Python binding, a thin layer over the C++ library.
// pneumo/__init__.py wraps what this returns (plain dicts and numpy arrays)
// into the Result, SweepResult and Component classes users see.
//
// Every call that runs C++ work releases the GIL; Python objects are made
// only after it is taken back. Runs and sweeps go through interruptible(),
// so that Ctrl-C stops them at the solver's next step. Input errors become pneumo.NetlistError with
// the CLI's message (file:line:column, component, parameter) and the parts
// as attributes.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <fstream>
#include <future>
#include <memory>
#include <sstream>
#include <thread>

#include "components/builtin.hpp"
#include "framework/analysis/energy_audit.hpp"
#include "framework/analysis/run_metrics.hpp"
#include "framework/core/interrupt.hpp"
#include "framework/core/parallel.hpp"
#include "framework/core/version.hpp"
#include "framework/run/model.hpp"
#include "framework/run/run.hpp"
#include "framework/study/sweep.hpp"

namespace py = pybind11;
using namespace pneumo;

namespace {

// A loaded netlist (framework/run/model.hpp: its text, each sweep thread
// parsing its own copy, the parsed netlist and the registry its `plugins:`
// make) and a lock held while anything reads the shared YAML nodes
// (elaboration, a sweep's design and metrics), so that Python threads may
// run one netlist at once.
class LoadedNetlist {
 public:
  // Validated in full, as a run would be: an unknown type, port or
  // parameter and a circuit without a consistent structure are errors here,
  // at pneumo.load(), not at the first simulate().
  explicit LoadedNetlist(const std::string& path) : model_(load_model(path, builtin_registry())) {
    try {
      const System assembled(elaborate(model_.netlist, model_.registry));
    } catch (const StructureError& e) {
      throw StructureError(path + ": " + e.what());  // as the CLI prints it
    }
  }

  const std::string& path() const { return model_.path; }
  const std::string& text() const { return model_.text; }
  const Netlist& netlist() const { return model_.netlist; }
  const Registry& registry() const { return model_.registry; }

 private:
  Model model_;
};

// Runs `work` (C++ only: it must not touch Python objects) on a thread of
// its own, while the calling thread takes the GIL every 50 ms to let Python
// handle its signals. Python runs its signal handlers only between
// bytecodes, so a KeyboardInterrupt would otherwise wait for the whole
// sweep; here Ctrl-C asks the C++ work to stop (the solver throws
// Interrupted at its next step) and raises KeyboardInterrupt once it has.
// Called from a thread other than Python's main one, PyErr_CheckSignals
// does nothing and the work simply runs to its end.
template <class Work>
auto interruptible(Work work) -> decltype(work()) {
  using Result = decltype(work());
  std::packaged_task<Result()> task(std::move(work));
  std::future<Result> done = task.get_future();
  std::thread worker(std::move(task));
  for (;;) {
    std::future_status status;
    {
      py::gil_scoped_release release;
      status = done.wait_for(std::chrono::milliseconds(50));
    }
    if (status == std::future_status::ready) break;
    if (PyErr_CheckSignals() != 0) {  // a handler raised (KeyboardInterrupt)
      request_interrupt();
      {
        py::gil_scoped_release release;
        worker.join();
      }
      clear_interrupt();
      throw py::error_already_set();
    }
  }
  worker.join();
  return done.get();  // the work's own exception, if it threw
}

// What `pneumo simulate` computes: the run, and every metric the netlist
// declares (integrals and audits as extra outputs, dropped afterwards).
struct Simulation {
  RunResult run;
  std::vector<std::string> metric_names, metric_units;
  std::vector<double> metric_values;
};

Simulation simulate(const LoadedNetlist& loaded, const std::vector<std::string>& sets) try {
  Simulation s;
  std::vector<AuditPlan> audits;
  std::unique_ptr<System> system;
  Netlist nl;
  {
    nl = loaded.netlist();
    for (const auto& a : sets) apply_override(nl, a);
    const std::vector<bool> all(nl.metrics.size(), true);
    add_metric_outputs(nl, all);
    Circuit circuit = elaborate(nl, loaded.registry());
    if (metrics_read_audit(nl, all)) audits = prepare_energy_audit(nl, circuit);
    system = std::make_unique<System>(std::move(circuit),
                                      AssemblyOptions{.rest_heat = nl.simulation.steady_start});
    for (const auto& d : metric_dimensions(nl, system->circuit())) s.metric_units.push_back(units::si_unit_name(d));
    (void)metric_units(nl, system->circuit());  // a declared unit that does not fit is an error here too
  }
  s.run = run_system(*system, solver_options(nl.simulation));
  if (s.run.solver.ok)
    s.metric_values = evaluate_metrics(nl, std::vector<bool>(nl.metrics.size(), true), s.run,
                                       energy_audit(audits, s.run));
  for (const auto& m : nl.metrics) s.metric_names.push_back(m.name);
  drop_audit_columns(s.run.table);
  drop_metric_columns(s.run.table);
  return s;
} catch (const StructureError& e) {
  throw StructureError(loaded.path() + ": " + e.what());  // as the CLI prints it
}

// The table's columns as rows of one (columns x rows) array: res["x"] is a
// contiguous view of its row, no copy per column.
py::array_t<double> columns_array(const ResultsTable& table) {
  const auto n_rows = static_cast<py::ssize_t>(table.rows.size());
  const auto n_cols = static_cast<py::ssize_t>(table.names.size());
  py::array_t<double> a({n_cols, n_rows});
  auto v = a.mutable_unchecked<2>();
  for (py::ssize_t r = 0; r < n_rows; ++r)
    for (py::ssize_t c = 0; c < n_cols; ++c) v(c, r) = table.rows[r][c];
  return a;
}

py::dict stats_dict(const SolverStats& s) {
  const std::pair<const char*, long> counts[] = {
      {"steps", s.steps}, {"residual_evals", s.residual_evals}, {"jacobian_evals", s.jacobian_evals},
      {"jacobian_recombinations", s.jacobian_recombinations},
      {"recombined_retries", s.recombined_retries}, {"nonlinear_iterations", s.nonlinear_iterations},
      {"nonlinear_failures", s.nonlinear_failures}, {"error_test_failures", s.error_test_failures},
      {"root_evals", s.root_evals}, {"reinitialisations", s.reinitialisations}, {"variables", s.variables},
      {"netlist_variables", s.netlist_variables}, {"explicit_variables", s.explicit_variables},
      {"nonzeros", s.nonzeros}};
  py::dict d;
  for (const auto& [name, value] : counts) d[name] = value;
  return d;
}

py::dict simulation_dict(const Simulation& s) {
  py::dict d;
  d["ok"] = s.run.solver.ok;
  d["message"] = s.run.solver.message;
  d["t_reached"] = s.run.solver.t_reached;
  d["names"] = s.run.table.names;
  d["units"] = s.run.table.units;
  d["data"] = columns_array(s.run.table);
  py::list events;
  for (const auto& e : s.run.solver.events) events.append(py::make_tuple(e.t, e.component, e.message, e.tag));
  d["events"] = events;
  d["stats"] = stats_dict(s.run.solver.stats);
  d["metric_names"] = s.metric_names;
  d["metric_units"] = s.metric_units;
  d["metric_values"] = s.metric_values;
  return d;
}

py::list parameters_list(const Netlist& nl) {
  py::list out;
  for (const auto& p : nl.parameters)
    out.append(py::make_tuple(p.name, p.si_value, units::si_unit_name(p.dim), p.where.to_string()));
  return out;
}

// The values of one --grid axis NAME=FROM:TO:COUNT (SI), as `pneumo sweep`
// spaces them; pneumo.sweep makes the full factorial of the axes.
std::vector<double> grid_axis(const LoadedNetlist& loaded, const std::string& name, const std::string& spec) {
  const study::Design one = study::grid_design(loaded.netlist(), loaded.registry(), {name + "=" + spec});
  std::vector<double> axis;
  for (const auto& s : one.samples) axis.push_back(s.front());
  return axis;
}

study::Design samples_from(const LoadedNetlist& loaded, const std::vector<std::string>& names,
                           const std::vector<std::vector<double>>& rows) {
  study::Design d;
  for (const auto& n : names) d.parameters.push_back(study::resolve_parameter(loaded.netlist(), loaded.registry(), n));
  study::refuse_repeated(loaded.netlist(), d.parameters, "pneumo.sweep names");
  for (const auto& r : rows) {
    if (r.size() != names.size())
      throw InputError(SourceLocation{loaded.path(), 1, 1}, "", "",
                       "pneumo.sweep: every sample needs " + std::to_string(names.size()) + " values, one per parameter");
    d.samples.push_back(r);
  }
  return d;
}

// Every sample run by pneumo::study::SweepRunner on `threads` threads, as
// run_sweep does (no journal, no file); the parsed netlist is shared.
std::vector<study::RunRecord> run_design(const LoadedNetlist& loaded, const study::Design& d,
                                         const std::vector<study::Metric>& metrics,
                                         const std::vector<std::string>& sets, int threads) {
  Netlist nl = loaded.netlist();
  for (const auto& a : sets) apply_override(nl, a);
  std::vector<study::RunRecord> records(d.samples.size());
  const study::SweepRunner runner(nl, loaded.registry(), d.parameters, metrics);
  parallel_for(static_cast<long>(d.samples.size()), threads, [&](int, long k) {
    records[k] = runner.run(d.samples[k]);
    records[k].index = k;
  });
  return records;
}

py::dict sweep_dict(const study::Design& d, const std::vector<study::Metric>& metrics,
                    const std::vector<study::RunRecord>& records) {
  const auto n = static_cast<py::ssize_t>(records.size());
  py::dict out;
  py::list params;
  for (std::size_t j = 0; j < d.parameters.size(); ++j) {
    py::array_t<double> a(n);
    auto v = a.mutable_unchecked<1>();
    for (py::ssize_t k = 0; k < n; ++k) v(k) = d.samples[k][j];
    params.append(py::make_tuple(d.parameters[j].name, d.parameters[j].unit, a));
  }
  py::list ms;
  for (std::size_t m = 0; m < metrics.size(); ++m) {
    py::array_t<double> a(n);
    auto v = a.mutable_unchecked<1>();
    for (py::ssize_t k = 0; k < n; ++k) v(k) = records[k].ok ? records[k].metrics[m] : std::nan("");
    ms.append(py::make_tuple(metrics[m].name, metrics[m].si_unit, a));  // Python keeps SI
  }
  py::array_t<bool> ok(n);
  py::array_t<long> steps(n);
  py::list reasons;
  for (py::ssize_t k = 0; k < n; ++k) {
    ok.mutable_at(k) = records[k].ok;
    steps.mutable_at(k) = records[k].steps;
    reasons.append(records[k].reason);
  }
  out["parameters"] = params;
  out["metrics"] = ms;
  out["ok"] = ok;
  out["steps"] = steps;
  out["reasons"] = reasons;
  return out;
}

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

py::dict component_dict(const ComponentInfo& info) {
  py::dict d;
  d["type"] = info.type;
  d["description"] = info.description;
  py::list ports, params, outputs;
  for (const auto& p : info.ports)
    ports.append(py::make_tuple(p.name, std::string(domain_name(p.domain)), p.description));
  for (const auto& p : info.parameters) {
    py::object def = py::none();
    if (p.kind == ParameterKind::scalar && p.default_value) def = py::float_(*p.default_value);
    if (p.kind == ParameterKind::text && p.default_text) def = py::str(*p.default_text);
    const char* kind = p.kind == ParameterKind::scalar ? "scalar" : p.kind == ParameterKind::table ? "table" : "text";
    params.append(py::make_tuple(p.name, p.unit, def, p.kind == ParameterKind::scalar ? p.range_text() : "", kind,
                                 p.description));
  }
  for (const auto& v : info.variables) outputs.append(py::make_tuple(v.name, v.unit, v.description));
  for (const auto& v : info.observables) outputs.append(py::make_tuple(v.name, v.unit, v.description));
  d["ports"] = ports;
  d["parameters"] = params;
  d["outputs"] = outputs;
  return d;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "pneumo's C++ library (use the pneumo package, not this module)";
  m.attr("__version__") = PNEUMO_VERSION_STRING;

  static py::exception<InputError> netlist_error(m, "NetlistError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      py::object exc = py::handle(netlist_error.ptr())(e.what());  // an instance, to carry the parts
      exc.attr("file") = e.where().file;
      exc.attr("line") = e.where().line;
      exc.attr("column") = e.where().column;
      exc.attr("component") = e.component();
      exc.attr("parameter") = e.parameter();
      PyErr_SetObject(netlist_error.ptr(), exc.ptr());
    } catch (const StructureError& e) {
      netlist_error(e.what());
    } catch (const Interrupted&) {  // Ctrl-C seen by another thread's call
      PyErr_SetString(PyExc_KeyboardInterrupt, "pneumo: the run was interrupted");
    }
  });

  py::class_<LoadedNetlist, std::shared_ptr<LoadedNetlist>>(m, "Netlist")
      .def(py::init([](const std::string& path) {
             py::gil_scoped_release release;
             return std::make_shared<LoadedNetlist>(path);
           }),
           py::arg("path"))
      .def_property_readonly("file", &LoadedNetlist::path)
      .def_property_readonly("parameters", [](const LoadedNetlist& l) { return parameters_list(l.netlist()); })
      .def_property_readonly("outputs",
                             [](const LoadedNetlist& l) {
                               std::vector<std::string> names;
                               for (const auto& o : l.netlist().outputs) names.push_back(o.name);
                               return names;
                             })
      .def_property_readonly("metrics",
                             [](const LoadedNetlist& l) {
                               std::vector<std::string> names;
                               for (const auto& x : l.netlist().metrics) names.push_back(x.name);
                               return names;
                             })
      .def(
          "simulate",
          [](const LoadedNetlist& l, const std::vector<std::string>& sets) {
            const Simulation s = interruptible([&] { return simulate(l, sets); });
            return simulation_dict(s);
          },
          py::arg("sets"));

  m.def(
      "grid_axis",
      [](const LoadedNetlist& l, const std::string& name, const std::string& spec) { return grid_axis(l, name, spec); },
      py::arg("netlist"), py::arg("name"), py::arg("spec"));
  m.def(
      "sweep",
      [](const LoadedNetlist& l, const std::vector<std::string>& names, const std::vector<std::vector<double>>& samples,
         const std::vector<std::string>& metric_names, const std::vector<std::string>& sets, int threads) {
        study::Design d;
        std::vector<study::Metric> metrics;
        const std::vector<study::RunRecord> records = interruptible([&] {
          d = samples_from(l, names, samples);
          metrics = study::select_metrics(l.netlist(), l.registry(), metric_names);
          return run_design(l, d, metrics, sets, threads);
        });
        return sweep_dict(d, metrics, records);
      },
      py::arg("netlist"), py::arg("names"), py::arg("samples"), py::arg("metrics"), py::arg("sets"),
      py::arg("threads"));

  // For benchmarks/python_overhead.py: the same runs timed in C++ alone.
  m.def(
      "time_runs",
      [](const LoadedNetlist& l, const std::vector<std::string>& sets, int runs) {
        std::vector<std::pair<double, double>> ms;
        py::gil_scoped_release release;
        for (int k = 0; k < runs; ++k) {
          const auto wall0 = std::chrono::steady_clock::now();
          const double cpu0 = thread_cpu_ms();
          const Simulation s = simulate(l, sets);
          const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall0).count();
          ms.emplace_back(wall, thread_cpu_ms() - cpu0);
        }
        return ms;
      },
      py::arg("netlist"), py::arg("sets"), py::arg("runs"));

  m.def("component_types", []() { return builtin_registry().types(); });
  m.def(
      "component",
      [](const std::string& type) {
        const auto* entry = builtin_registry().find(type);
        if (!entry) throw py::key_error("no component type '" + type + "' (pneumo.components() lists them)");
        return component_dict(*entry->info);
      },
      py::arg("type"));
}
