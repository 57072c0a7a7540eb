// Cost of one run of netlists/cushion_rig.yaml (1.2 s stroke, rtol 1e-6) on
// one thread, against the floor: the hand-written IDA + KLU program of the
// same equations in tests/reference (analytic Jacobian, 10 states, no
// framework). Prints the median CPU time of many runs, IDA's statistics of
// both, and the ratio framework / floor - like for like, both with pneumo's
// compiled N_Vector kernels, and against the floor as written.
//
//   cushion_rig_benchmark [runs] [netlist]
//
// Framework figures: "solve" reuses one assembled System (what a
// parameter study pays when only start values change), "elaborate + solve"
// builds the circuit and System from the parsed netlist each run (what
// `pneumo sweep` pays per run), "elaborate" alone, and "solve" of the
// System assembled without alias elimination (every unknown of the
// netlist handed to IDA, as `--keep-aliases`), for comparison. Both the
// framework and the floor are timed with and without reuse of the Newton
// matrix (SolverOptions::jacobian_reuse, the framework's default); the
// target ratio is taken against the faster floor.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <sys/resource.h>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "cushion_rig_reference.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "framework/solver/serial_vector_ops.hpp"

namespace {

using Clock = std::chrono::steady_clock;

// CPU time of this thread, in ms: on a machine shared with other jobs the
// wall time of a run includes waiting for a core; the CPU time does not.
// Both are reported; the figures docs/benchmarks.md quotes are CPU time.
double cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

struct Stopwatch {
  Clock::time_point wall0 = Clock::now();
  double cpu0 = cpu_ms();
};

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct Timing {
  double median = 0, min = 0, p90 = 0;
};

Timing summarise(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  Timing t;
  t.median = v[v.size() / 2];
  t.min = v.front();
  t.p90 = v[std::min(v.size() - 1, v.size() * 9 / 10)];
  return t;
}

void print_timing(const char* what, const Timing& t) {
  std::printf("  %-34s median %7.3f ms   min %7.3f ms   p90 %7.3f ms\n", what, t.median, t.min, t.p90);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pneumo;
  const int runs = argc > 1 ? std::max(3, std::atoi(argv[1])) : 50;
  const std::string path = argc > 2 ? argv[2] : std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml";

  const Netlist nl = load_netlist(path);
  const SolverOptions opt = solver_options(nl.simulation);
  SolverOptions opt_fresh = opt;
  opt_fresh.jacobian_reuse = false;
  std::printf("cushion rig benchmark: %s, t_end %.3g s, rtol %.1e, output every %.3g s, %d runs, one thread\n",
              path.c_str(), opt.t_end, opt.rtol, opt.output_interval, runs);

  // Warm-up (page faults, caches) and statistics of one run.
  System system(elaborate(nl, builtin_registry()));
  RunResult first = run_system(system, opt);
  if (!first.solver.ok) {
    std::fprintf(stderr, "framework run failed: %s\n", first.solver.message.c_str());
    return 1;
  }

  AssemblyOptions keep;
  keep.eliminate_aliases = false;
  System all_unknowns(elaborate(nl, builtin_registry()), keep);
  RunResult first_all = run_system(all_unknowns, opt);
  RunResult first_fresh = run_system(system, opt_fresh);

  // Wall and CPU milliseconds of each timed call.
  std::vector<double> solve_ms, full_ms, elab_ms, ref_ms, all_ms, fresh_ms;
  std::vector<double> solve_cpu, full_cpu, ref_cpu, all_cpu, fresh_cpu;
  auto timed = [](std::vector<double>& wall, std::vector<double>& cpu, auto&& body) {
    const auto t0 = Clock::now();
    const double c0 = cpu_ms();
    body();
    cpu.push_back(cpu_ms() - c0);
    wall.push_back(ms_since(t0));
  };
  bool ok = true;
  for (int k = 0; k < runs; ++k) {
    timed(solve_ms, solve_cpu, [&] { ok &= run_system(system, opt).solver.ok; });
    timed(all_ms, all_cpu, [&] { ok &= run_system(all_unknowns, opt).solver.ok; });
    timed(fresh_ms, fresh_cpu, [&] { ok &= run_system(system, opt_fresh).solver.ok; });
    std::vector<double> unused;
    timed(full_ms, full_cpu, [&] {
      const auto t0 = Clock::now();
      System s2(elaborate(nl, builtin_registry()));
      elab_ms.push_back(ms_since(t0));
      ok &= run_system(s2, opt).solver.ok;
    });
  }
  if (!ok) {
    std::fprintf(stderr, "a framework run failed\n");
    return 1;
  }

  // The floor, at the rig's defaults (the netlist's values).
  pneumo_reference::RigParams P;
  pneumo_reference::RigResult ref = pneumo_reference::simulate(P, opt.t_end, opt.rtol, opt.output_interval);
  // Like for like: the floor with the vector kernels pneumo uses (Debian's
  // serial N_Vector is built unoptimised; see serial_vector_ops.hpp).
  std::vector<double> ref_fast_ms, ref_fast_cpu, ref_reuse_ms, ref_reuse_cpu;
  pneumo_reference::RigResult ref_reuse =
      pneumo_reference::simulate(P, opt.t_end, opt.rtol, opt.output_interval, use_compiled_serial_ops, true);
  for (int k = 0; k < runs; ++k) {
    timed(ref_ms, ref_cpu, [&] { ref = pneumo_reference::simulate(P, opt.t_end, opt.rtol, opt.output_interval); });
    timed(ref_fast_ms, ref_fast_cpu, [&] {
      ref = pneumo_reference::simulate(P, opt.t_end, opt.rtol, opt.output_interval, use_compiled_serial_ops);
    });
    timed(ref_reuse_ms, ref_reuse_cpu, [&] {
      ref_reuse = pneumo_reference::simulate(P, opt.t_end, opt.rtol, opt.output_interval, use_compiled_serial_ops, true);
    });
  }

  const auto& s = first.solver.stats;
  std::printf("\nframework (%d variables, %ld Jacobian nonzeros, %zu events):\n", s.variables, s.nonzeros,
              first.solver.events.size());
  std::printf("  steps %ld, residual evaluations %ld, Jacobian evaluations %ld (two AD passes each) and %ld\n"
              "  recombined from their parts, re-initialisations %ld,\n"
              "  nonlinear iterations %ld, convergence failures %ld, error test failures %ld, root evaluations %ld\n",
              s.steps, s.residual_evals, s.jacobian_evals, s.jacobian_recombinations, s.reinitialisations,
              s.nonlinear_iterations, s.nonlinear_failures, s.error_test_failures, s.root_evals);
  const Timing solve = summarise(solve_cpu), full = summarise(full_cpu), elab = summarise(elab_ms);
  print_timing("solve (System reused), CPU", solve);
  print_timing("solve (System reused), wall", summarise(solve_ms));
  print_timing("elaborate + solve, CPU", full);
  print_timing("elaborate only, wall", elab);
  const auto& sf = first_fresh.solver.stats;
  std::printf("framework, every Newton matrix evaluated afresh (jacobian_reuse = false):\n");
  std::printf("  steps %ld, residual evaluations %ld, Jacobian evaluations %ld, convergence failures %ld\n", sf.steps,
              sf.residual_evals, sf.jacobian_evals, sf.nonlinear_failures);
  const Timing fresh = summarise(fresh_cpu);
  print_timing("solve (System reused), CPU", fresh);
  const auto& sr = first_all.solver.stats;
  std::printf("framework without alias elimination (--keep-aliases, %d variables, %ld nonzeros; %s):\n", sr.variables,
              sr.nonzeros, first_all.solver.ok ? "ok" : first_all.solver.message.c_str());
  std::printf("  steps %ld, residual evaluations %ld, Jacobian evaluations %ld\n", sr.steps, sr.residual_evals,
              sr.jacobian_evals);
  const Timing all = summarise(all_cpu);
  print_timing("solve (System reused), CPU", all);
  print_timing("solve (System reused), wall", summarise(all_ms));

  const auto& rs = ref.stats;
  std::printf("\nfloor: hand-written IDA + KLU (tests/reference, 10 states, analytic Jacobian):\n");
  std::printf("  steps %ld, residual evaluations %ld, Jacobian evaluations %ld, error test failures %ld,\n"
              "  convergence failures %ld\n",
              rs.steps, rs.residual_evals, rs.jacobian_evals, rs.error_test_failures, rs.nonlinear_conv_failures);
  const Timing floor_debian = summarise(ref_cpu), floor = summarise(ref_fast_cpu);
  print_timing("solve, CPU (pneumo's vector kernels)", floor);
  print_timing("solve, wall (pneumo's vector kernels)", summarise(ref_fast_ms));
  print_timing("solve, CPU (Debian's N_Vector)", floor_debian);
  const auto& ru = ref_reuse.stats;
  std::printf("floor with the framework's Newton matrix reuse:\n");
  std::printf("  steps %ld, residual evaluations %ld, Jacobian evaluations %ld and %ld recombined, "
              "convergence failures %ld\n",
              ru.steps, ru.residual_evals, ru.jacobian_evals, ru.jacobian_recombinations, ru.nonlinear_conv_failures);
  const Timing floor_reuse = summarise(ref_reuse_cpu);
  print_timing("solve, CPU (pneumo's vector kernels)", floor_reuse);
  const Timing best_floor = floor_reuse.median < floor.median ? floor_reuse : floor;

  std::printf("\nratio framework / floor, both with pneumo's vector kernels (CPU medians):\n"
              "  both reusing the Newton matrix: solve %.2f, elaborate + solve %.2f, without alias elimination %.2f\n"
              "  neither reusing it: solve %.2f\n"
              "  against the faster floor: solve %.2f\n",
              solve.median / floor_reuse.median, full.median / floor_reuse.median, all.median / floor_reuse.median,
              fresh.median / floor.median, solve.median / best_floor.median);
  std::printf("ratio framework / faster floor (CPU minima): solve %.2f\n", solve.min / std::min(floor.min, floor_reuse.min));
  std::printf("ratio framework / floor as written (Debian's N_Vector, CPU medians): solve %.2f\n",
              solve.median / floor_debian.median);
  std::printf("targets (issue #7): 5 ms per stroke -> %s (%.2f ms); framework <= 1.5 x floor (like for like) -> %s "
              "(%.2f)\n",
              solve.median <= 5.0 ? "met" : "NOT met", solve.median,
              solve.median <= 1.5 * best_floor.median ? "met" : "NOT met", solve.median / best_floor.median);
  const double per_run = full.median;  // elaborate + solve: what a sweep pays per run
  std::printf("nominal run, elaborate + solve: %.1f runs/s per core; 100,000 runs: %.0f min on one core, "
              "%.0f min on two (runs are independent)\n",
              1e3 / per_run, 1e5 * per_run / 6e4, 1e5 * per_run / 6e4 / 2);
  std::printf("per residual evaluation: framework %.2f us, floor %.2f us (whole run / residual evaluations)\n",
              1e3 * solve.median / std::max(1L, s.residual_evals),
              1e3 * best_floor.median / std::max(1L, (floor_reuse.median < floor.median ? ru : rs).residual_evals));
  // Memory: the results table of one run, and the whole process's peak.
  const std::size_t table_bytes = first.table.rows.size() * (first.table.names.size() * sizeof(double) + 24);
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("memory: results of one run %zu rows x %zu columns (~%.0f kB); peak resident set of this process "
              "%.1f MB\n",
              first.table.rows.size(), first.table.names.size(), table_bytes / 1024.0, usage.ru_maxrss / 1024.0);
  return 0;
}
