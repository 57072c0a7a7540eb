// Cost of the sequence netlists: netlists/sequence_ab.yaml (2 cylinders,
// 1.5 s) and netlists/assembly_line.yaml (6 cylinders, 2.5 s), each run
// elaborated and solved on one thread. Prints the median and least CPU and
// wall time over the runs, the cycle (takt) time the sequencer reports, and
// the solver's counts - the figures docs/benchmarks.md quotes for the takt.
//
//   sequence_benchmark [runs]       (default 10)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace {

// CPU time of this thread, ms (on a shared machine the wall time includes
// waiting for a core).
double cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void bench(const char* name, int runs) {
  const pneumo::Netlist nl = pneumo::load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/" + name + ".yaml");
  std::vector<double> cpu, wall;
  pneumo::RunResult last;
  for (int i = 0; i < runs; ++i) {
    const auto w0 = std::chrono::steady_clock::now();
    const double c0 = cpu_ms();
    last = pneumo::run_simulation(nl, pneumo::builtin_registry());
    cpu.push_back(cpu_ms() - c0);
    wall.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - w0).count());
    if (!last.solver.ok) {
      std::printf("%s: run failed: %s\n", name, last.solver.message.c_str());
      std::exit(1);
    }
  }
  double start = -1, end = -1;
  for (const auto& e : last.solver.events) {
    if (e.tag == "cycle_start" && start < 0) start = e.t;
    if (e.tag == "cycle_end" && end < 0) end = e.t;
  }
  const auto& s = last.solver.stats;
  std::printf("%-14s simulated %.1f s, cycle time %.4f s | CPU median %.1f ms (least %.1f), wall median %.1f ms "
              "(least %.1f) over %d runs | steps %ld, residuals %ld, Jacobians %ld, events %zu\n",
              name, nl.simulation.t_end - nl.simulation.t_start, end - start, median(cpu),
              *std::min_element(cpu.begin(), cpu.end()), median(wall), *std::min_element(wall.begin(), wall.end()),
              runs, s.steps, s.residual_evals, s.jacobian_evals, last.solver.events.size());
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 10;
  bench("sequence_ab", runs);
  bench("assembly_line", runs);
  return 0;
}
