// Many runs of one netlist in one process (threads) or across MPI ranks,
// with scalar metrics per run, a journal that makes a killed sweep
// resumable, and failed runs recorded with their reason.
//
// Journal: OUT.journal (OUT.journal.rankR under MPI), one line per finished
// run "index,status,metrics...,steps,reason", written with one fwrite and
// flushed as the run finishes. Its first line identifies the sweep (a hash of
// the netlist text, parameters, samples and metrics); a restarted sweep with
// the same identity skips every index already in a journal, so no run is lost
// or done twice; a different sweep refuses to reuse it. A line cut short by a
// kill is ignored and its run done again. When all runs are done, the results
// are written to OUT.writing, renamed to OUT (ordered by run index), and the
// journals are removed.
#pragma once

#include <string>
#include <vector>

#include "framework/run/model.hpp"
#include "framework/study/communicator.hpp"
#include "framework/study/metrics.hpp"
#include "framework/study/parameters.hpp"

namespace pneumo::study {

struct RunRecord {
  long index = -1;
  bool ok = false;
  std::vector<double> metrics;  // NaN where undefined; empty if !ok
  long steps = 0;
  std::string reason;  // why it failed
};

struct SweepOptions {
  int threads = 1;
  bool progress = true;                // progress bar on stderr (rank 0)
  std::vector<std::string> metrics;    // names; empty = all the netlist can provide
  bool keep_journal = false;           // for tests: do not delete the journals at the end
  long stop_after = -1;                // for tests: stop (as if killed) after this many new runs
  AssemblyOptions assembly;            // alias elimination (default on)
};

// Whether a first line is the header of a sweep's results file.
bool is_sweep_results_header(const std::string& first_line);

struct SweepSummary {
  long runs = 0;        // in the design
  long done_before = 0; // found in journals (resumed)
  long computed = 0;    // run now (this rank)
  long failed = 0;      // in the final results (rank 0)
  bool complete = false;
  double seconds = 0.0;
  int ranks = 1;        // MPI ranks that shared the sweep
  std::vector<RunRecord> records;  // rank 0, complete sweeps: ordered by index
};

// Runs every sample of `design` on `model` (its components from the model's
// registry). Returns the records (all of them on rank 0 when complete).
// Throws InputError for bad input found before any run.
SweepSummary run_sweep(const Model& model, const Design& design, const std::string& output,
                       const SweepOptions& options, Communicator& comm);

// The runs of one study of `netlist`: what every run shares (the metrics'
// plan and the hidden outputs they read) prepared once; run() is safe to
// call from several threads at once.
class SweepRunner {
 public:
  SweepRunner(const Netlist& netlist, const Registry& registry, std::vector<StudyParameter> parameters,
              std::vector<Metric> metrics, const AssemblyOptions& assembly = {});
  // One run with the sample's values set (on a copy of the netlist): never
  // throws for a failing run (bad parameter combination, solver failure):
  // the record says why.
  RunRecord run(const Sample& sample) const;

 private:
  Netlist netlist_;  // with the metrics' outputs
  const Registry& registry_;
  std::vector<StudyParameter> parameters_;
  std::vector<Metric> metrics_;
  AssemblyOptions assembly_;
  MetricPlan plan_;
};

// One run of `netlist` with the given parameter values set (as values, on a
// copy): never throws for a failing run (bad parameter combination, solver
// failure): the record says why.
RunRecord run_one(const Netlist& netlist, const Registry& registry, const std::vector<StudyParameter>& parameters,
                  const Sample& sample, const std::vector<Metric>& metrics,
                  const AssemblyOptions& assembly = {});

// Why runs failed, for a message: each distinct reason once with how many
// runs gave it (at most `shown` reasons, most frequent first).
std::string failure_summary(const std::vector<RunRecord>& records, std::size_t shown = 5);

// The results file written by run_sweep, read back (for tests and tools).
struct SweepTable {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;  // cells as written
};
SweepTable read_sweep_csv(const std::string& path);

}  // namespace pneumo::study
