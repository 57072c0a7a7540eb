// Cost of a run against the size of the circuit, for netlists/cushion_rig.yaml
// repeated N times:
//
//  * "copies": N copies with nothing shared (each its own supply, supply
//    pressure and cushion throttle setting), N = 1, 2, 4, ..., integrated as
//    N independent parts (run_circuit) on one thread and on two, and - for
//    comparison - as one System with one IDA (what every netlist paid
//    before);
//  * "line": N cylinders on one supply (one coupled part), N = 1, 2, ..., 16
//    (a node of 33 pneumatic ports exceeds assembly's limit of locals a block).
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
};

enum class Mode { parts, one_system };

// `runs` runs of the netlist; the medians.
Figure measure(const Netlist& nl, Mode mode, int threads, int runs) {
  std::vector<double> wall, cpu;
  Figure f;
  for (int r = 0; r < runs; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = process_cpu_ms();
    SolverOptions opt = solver_options(nl.simulation);
    opt.threads = threads;
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
  }
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

// Copy k's own supply pressure and cushion throttle setting.
void vary(int k, YAML::Node p) {
  p["p_supply"] = std::to_string(4.0 + 0.25 * (k % 9)) + " bar";
  p["z_EC"] = std::to_string(0.8 + 0.3 * (k % 8)) + " rev";
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  const int max_copies = argc > 2 ? std::atoi(argv[2]) : 128;
  // N = 32 on one supply joins 33 pneumatic ports at the supply's node,
  // past assembly's limit of locals a block (an input error): not run.
  const int max_line = argc > 3 ? std::atoi(argv[3]) : 16;
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
  const auto at = [&](int n) { return std::find(ns.begin(), ns.end(), n) - ns.begin(); };
  if (static_cast<std::size_t>(at(64)) < ns.size() && static_cast<std::size_t>(at(8)) < ns.size())
    std::printf("per copy, N = 64 over N = 8: parts 1 thread %.3f, parts 2 threads %.3f, one System %.3f\n",
                split1[at(64)] / 64 / (split1[at(8)] / 8), split2[at(64)] / 64 / (split1[at(8)] / 8),
                whole[at(64)] / 64 / (whole[at(8)] / 8));
  if (static_cast<std::size_t>(at(64)) < ns.size() && static_cast<std::size_t>(at(8)) < ns.size())
    std::printf("per copy, N = 64 over N = 8, CPU time (no waiting for a core): parts 1 thread %.3f\n",
                split1_cpu[at(64)] / 64 / (split1_cpu[at(8)] / 8));

  std::vector<int> nl_ns;
  std::vector<double> line;
  std::printf("N cylinders on one supply (one coupled part)\n");
  for (int n = 1; n <= max_line; n *= 2) {
    const Netlist nl = parse_netlist(pneumo_scale::copies_netlist(rig, n, vary, "supply"), "line.yaml");
    const Figure f = measure(nl, Mode::parts, 1, runs);
    print_row("line", n, f);
    nl_ns.push_back(n);
    line.push_back(f.wall);
  }
  if (nl_ns.size() > 1) std::printf("fit wall ~ N^a: line a = %.3f\n", exponent(nl_ns, line));
  return 0;
}
