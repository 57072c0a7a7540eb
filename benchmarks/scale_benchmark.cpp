// Cost of a run against the size of the circuit, for netlists/cushion_rig.yaml
// repeated N times:
//
//  * "copies": N copies with nothing shared (each its own supply, supply
//    pressure and cushion throttle setting), N = 1, 2, 4, ..., integrated as
//    N independent parts (run_circuit) on one thread and on two, and - for
//    comparison - as one System with one IDA (what every netlist paid
//    before);
//  * "line": N cylinders on one supply (one coupled part), N = 1, 2, ..., 64,
//    with where its cost goes: IDA's steps, Newton iterations, residuals,
//    Newton matrices (evaluated, recombined), LU factorisations (with a new
//    ordering), refactorisations and solves, and the time shares of the
//    residual, the Newton matrix (AD), the LU setup and solve and the rest
//    (SolverStats), each with the exponent of its fit ~ N^a.
//
// Each figure: the median of `runs` runs of elaborate + assemble + integrate;
// wall and CPU time (of the process: all threads), IDA steps (the sum over
// parts and the largest part's), the peak resident memory so far, and the
// exponent a of the least-squares fit wall ~ N^a.
//
//   scale_benchmark [runs] [max copies] [max line]
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "benchmarks/copies_netlist.hpp"
#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace {

using namespace pneumo;

double process_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;
}

struct Figure {
  double wall = 0, cpu = 0;  // ms, medians
  long steps = 0, steps_max = 0;
  int parts = 0;
  SolverStats stats;  // of the run with the median wall time
};

enum class Mode { parts, one_system };

// `runs` runs of the netlist; the medians.
Figure measure(const Netlist& nl, Mode mode, int threads, int runs) {
  std::vector<double> wall, cpu;
  std::vector<SolverStats> stats;
  Figure f;
  for (int r = 0; r < runs; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = process_cpu_ms();
    SolverOptions opt = solver_options(nl.simulation);
    opt.threads = threads;
    opt.time_phases = true;  // the cost breakdown below
    RunResult run;
    if (mode == Mode::parts) {
      run = run_circuit(elaborate(nl, builtin_registry()), opt);
    } else {
      System system(elaborate(nl, builtin_registry()));
      run = run_system(system, opt);
    }
    cpu.push_back(process_cpu_ms() - c0);
    wall.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (!run.solver.ok) {
      std::fprintf(stderr, "run failed: %s\n", run.solver.message.c_str());
      std::exit(1);
    }
    f.steps = run.solver.stats.steps;
    f.steps_max = run.solver.stats.part_steps_max;
    f.parts = run.solver.stats.parts;
    stats.push_back(run.solver.stats);
  }
  std::vector<std::size_t> order(wall.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return wall[a] < wall[b]; });
  f.stats = stats[order[order.size() / 2]];
  std::sort(wall.begin(), wall.end());
  std::sort(cpu.begin(), cpu.end());
  f.wall = wall[wall.size() / 2];
  f.cpu = cpu[cpu.size() / 2];
  return f;
}

// Least-squares slope of log(cost) over log(N).
double exponent(const std::vector<int>& n, const std::vector<double>& cost) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double m = static_cast<double>(n.size());
  for (std::size_t i = 0; i < n.size(); ++i) {
    const double x = std::log(n[i]), y = std::log(cost[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  return (m * sxy - sx * sy) / (m * sxx - sx * sx);
}

void print_row(const char* what, int n, const Figure& f) {
  std::printf("  %-22s N %4d  parts %4d  wall %9.1f ms (%6.2f ms/copy)  cpu %9.1f ms  steps %8ld (max %6ld)  "
              "peak RSS %7.1f MB\n",
              what, n, f.parts, f.wall, f.wall / n, f.cpu, f.steps, f.steps_max, peak_rss_mb());
  std::fflush(stdout);
}

// One cost of the line against N, with its fitted exponent.
void print_cost(const char* what, const std::vector<int>& ns, const std::vector<Figure>& figs,
                const std::function<double(const Figure&)>& cost, const char* format) {
  std::vector<double> v;
  std::printf("  %-28s", what);
  for (const auto& f : figs) {
    v.push_back(std::max(cost(f), 1e-9));
    std::printf(format, cost(f));
  }
  if (ns.size() > 1) std::printf("   a = %5.2f", exponent(ns, v));
  std::printf("\n");
}

// Where the line's cost goes (the run with the median wall time of each N).
void print_breakdown(const std::vector<int>& ns, const std::vector<Figure>& figs) {
  if (figs.empty()) return;
  std::printf("where the line's time goes (the median run of each N; a: exponent of the fit ~ N^a)\n  %-28s", "N");
  for (int n : ns) std::printf(" %9d", n);
  std::printf("\n");
  const char* count = " %9.0f";
  const char* ms = " %9.1f";
  const char* share = " %8.1f%%";
  using F = const Figure&;
  print_cost("wall (ms)", ns, figs, [](F f) { return f.wall; }, ms);
  print_cost("CPU (ms)", ns, figs, [](F f) { return f.cpu; }, ms);
  print_cost("unknowns of IDA", ns, figs, [](F f) { return double(f.stats.variables); }, count);
  print_cost("Newton matrix nonzeros", ns, figs, [](F f) { return double(f.stats.nonzeros); }, count);
  print_cost("steps", ns, figs, [](F f) { return double(f.stats.steps); }, count);
  print_cost("re-initialisations", ns, figs, [](F f) { return double(f.stats.reinitialisations); }, count);
  print_cost("Newton iterations", ns, figs, [](F f) { return double(f.stats.nonlinear_iterations); }, count);
  print_cost("residuals", ns, figs, [](F f) { return double(f.stats.residual_evals); }, count);
  print_cost("Newton matrices evaluated", ns, figs, [](F f) { return double(f.stats.jacobian_evals); }, count);
  print_cost("  recombined", ns, figs, [](F f) { return double(f.stats.jacobian_recombinations); }, count);
  print_cost("LU factorisations", ns, figs, [](F f) { return double(f.stats.lu.factorisations); }, count);
  print_cost("  with a new ordering", ns, figs, [](F f) { return double(f.stats.lu.analyses); }, count);
  print_cost("LU refactorisations", ns, figs, [](F f) { return double(f.stats.lu.refactorisations); }, count);
  print_cost("LU solves", ns, figs, [](F f) { return double(f.stats.lu.solves); }, count);
  const auto rest = [](F f) {
    const auto& s = f.stats;
    return s.seconds_total - s.seconds_residual - s.seconds_jacobian - s.lu.setup_seconds - s.lu.solve_seconds;
  };
  print_cost("integration (ms)", ns, figs, [](F f) { return 1e3 * f.stats.seconds_total; }, ms);
  print_cost("  residual (ms)", ns, figs, [](F f) { return 1e3 * f.stats.seconds_residual; }, ms);
  print_cost("  Newton matrix, AD (ms)", ns, figs, [](F f) { return 1e3 * f.stats.seconds_jacobian; }, ms);
  print_cost("  LU setup (ms)", ns, figs, [](F f) { return 1e3 * f.stats.lu.setup_seconds; }, ms);
  print_cost("  LU solve (ms)", ns, figs, [](F f) { return 1e3 * f.stats.lu.solve_seconds; }, ms);
  print_cost("  rest (ms)", ns, figs, [&](F f) { return 1e3 * rest(f); }, ms);
  const auto of_total = [](double part, F f) { return 100.0 * part / f.stats.seconds_total; };
  print_cost("  residual share", ns, figs, [&](F f) { return of_total(f.stats.seconds_residual, f); }, share);
  print_cost("  Newton matrix share", ns, figs, [&](F f) { return of_total(f.stats.seconds_jacobian, f); }, share);
  print_cost("  LU setup share", ns, figs, [&](F f) { return of_total(f.stats.lu.setup_seconds, f); }, share);
  print_cost("  LU solve share", ns, figs, [&](F f) { return of_total(f.stats.lu.solve_seconds, f); }, share);
  print_cost("  rest share", ns, figs, [&](F f) { return of_total(rest(f), f); }, share);
  print_cost("per residual (us)", ns, figs,
             [](F f) { return 1e6 * f.stats.seconds_residual / f.stats.residual_evals; }, ms);
  print_cost("per Newton matrix (us)", ns, figs,
             [](F f) { return 1e6 * f.stats.seconds_jacobian / std::max(1L, f.stats.jacobian_evals); }, ms);
  print_cost("per LU setup (us)", ns, figs,
             [](F f) { return 1e6 * f.stats.lu.setup_seconds / std::max(1L, f.stats.lu.refactorisations + f.stats.lu.analyses); }, ms);
  print_cost("per LU solve (us)", ns, figs,
             [](F f) { return 1e6 * f.stats.lu.solve_seconds / std::max(1L, f.stats.lu.solves); }, ms);
}

// Copy k's own supply pressure and cushion throttle setting.
void vary(int k, YAML::Node p) {
  p["p_supply"] = std::to_string(4.0 + 0.25 * (k % 9)) + " bar";
  p["z_EC"] = std::to_string(0.8 + 0.3 * (k % 8)) + " rev";
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  const int max_copies = argc > 2 ? std::atoi(argv[2]) : 128;
  const int max_line = argc > 3 ? std::atoi(argv[3]) : 64;
  std::ifstream file(std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml");
  std::stringstream text;
  text << file.rdbuf();
  const std::string rig = text.str();
  std::printf("scale benchmark: netlists/cushion_rig.yaml repeated N times, median of %d runs "
              "(elaborate + assemble + integrate)\n",
              runs);

  std::vector<int> ns;
  std::vector<double> split1, split2, whole, split1_cpu;
  std::printf("N independent copies\n");
  for (int n = 1; n <= max_copies; n *= 2) {
    const Netlist nl = parse_netlist(pneumo_scale::copies_netlist(rig, n, vary), "copies.yaml");
    const Figure one = measure(nl, Mode::parts, 1, runs);
    print_row("parts, 1 thread", n, one);
    const Figure two = measure(nl, Mode::parts, 2, runs);
    print_row("parts, 2 threads", n, two);
    const Figure sys = measure(nl, Mode::one_system, 1, runs);
    print_row("one System", n, sys);
    ns.push_back(n);
    split1.push_back(one.wall);
    split1_cpu.push_back(one.cpu);
    split2.push_back(two.wall);
    whole.push_back(sys.wall);
  }
  if (ns.size() > 1)
    std::printf("fit wall ~ N^a: parts 1 thread a = %.3f, parts 2 threads a = %.3f, one System a = %.3f\n",
                exponent(ns, split1), exponent(ns, split2), exponent(ns, whole));
  if (ns.size() > 1) std::printf("fit CPU ~ N^a: parts 1 thread a = %.3f\n", exponent(ns, split1_cpu));
  const auto at = [&](int n) { return std::find(ns.begin(), ns.end(), n) - ns.begin(); };
  if (static_cast<std::size_t>(at(64)) < ns.size() && static_cast<std::size_t>(at(8)) < ns.size())
    std::printf("per copy, N = 64 over N = 8: parts 1 thread %.3f, parts 2 threads %.3f, one System %.3f\n",
                split1[at(64)] / 64 / (split1[at(8)] / 8), split2[at(64)] / 64 / (split1[at(8)] / 8),
                whole[at(64)] / 64 / (whole[at(8)] / 8));
  if (static_cast<std::size_t>(at(64)) < ns.size() && static_cast<std::size_t>(at(8)) < ns.size())
    std::printf("per copy, N = 64 over N = 8, CPU time (no waiting for a core): parts 1 thread %.3f\n",
                split1_cpu[at(64)] / 64 / (split1_cpu[at(8)] / 8));

  std::vector<int> nl_ns;
  std::vector<Figure> line;
  std::printf("N cylinders on one supply (one coupled part)\n");
  for (int n = 1; n <= max_line; n *= 2) {
    const Netlist nl = parse_netlist(pneumo_scale::copies_netlist(rig, n, vary, "supply"), "line.yaml");
    const Figure f = measure(nl, Mode::parts, 1, runs);
    print_row("line", n, f);
    nl_ns.push_back(n);
    line.push_back(f);
  }
  print_breakdown(nl_ns, line);
  return 0;
}
