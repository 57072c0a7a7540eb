// The diagnosis's engine (framework/diagnose/diagnose.cpp's only helper
// class): the model and its patched variants, their runs at the measured
// operating points, normalised residuals, gap tables, the whitened
// significance test, the fits (framework/fit/bounded_lm.hpp) and the phases.
#pragma once

#include <Eigen/Dense>
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "framework/diagnose/diagnose.hpp"
#include "framework/diagnose/memo.hpp"
#include "framework/diagnose/phases.hpp"
#include "framework/run/model.hpp"
#include "framework/run/run.hpp"
#include "framework/solver/ida_solver.hpp"

namespace pneumo::diagnose::engine {

constexpr long kDisturbedMaxSteps = 20000;  // a disturbed run's step budget (the cushion rig's nominal run takes 1225)
// A disturbed run resumed from a kept run may take at most this many times
// the kept run's steps in all: a disturbance that has the model crawl at a
// fine step all the way reaches every output, so only the total shows it -
// and one such run costs as much as a dozen sound ones.
constexpr long kDisturbedStepsPerKept = 5;
constexpr double kFailedResidual = 1e4;  // per sample, for a run the solver could not finish
constexpr std::size_t kMemoValues = std::size_t{1} << 23;  // remembered signal values (64 MB)
constexpr std::size_t kKeptCheckpoints = 250;  // the unpatched run's checkpoints (Engine::unpatched_kept), at most
constexpr std::size_t kAssembledModels = 64;  // Systems kept for disturbed runs (Engine::assembled)

// One measured signal of one run inside a concatenated residual vector.
struct Segment {
  int run = 0, signal = 0;  // signal: index into the run's signals
  std::size_t offset = 0, n = 0;
};

struct Layout {
  std::vector<int> runs;  // indices into all runs
  std::vector<Segment> segments;
  std::size_t size = 0;
};

// Top-level parameters set on top of a run's operating point (SI values).
using Setting = std::vector<std::pair<std::string, double>>;

struct Model {  // a patched model ready to run
  Netlist netlist;
  MeasurementModel measurement;
  std::vector<RunFactor> run_factors;  // set on each run's netlist after its operating point
  // Its effects' instances as the memo names them; none: not remembered.
  std::optional<std::string> memo_key;
};

class Engine {
 public:
  // `base`: the registry the model's plugins are added to. Input errors of
  // the model are thrown here.
  Engine(const std::string& model_file, const Registry& base, const DiagnoseOptions& options);

  const Netlist& base() const { return loaded_.netlist; }
  const std::vector<Probe>& base_probes() const { return base_probes_; }
  const DiagnoseOptions& options() const { return options_; }
  const Registry& registry() const { return loaded_.registry; }

  std::vector<MeasuredRun> runs;
  std::vector<std::string> phase_names;
  std::vector<std::vector<int>> phases;            // per run, per sample
  std::vector<std::vector<double>> phase_times;    // per run: each phase's start, then the run's end
  std::atomic<long> simulations{0};

  Model model(const std::vector<EffectInstance>& effects) const;

  // Learns which of the candidates leave the model exactly as it is at
  // their null (vanishes_at_null): model() leaves such instances out of the
  // memo's name, so that the unpatched model's runs serve every candidate
  // at its null. Before the first run.
  void learn_nulls(const std::vector<Effect>& effects);
  std::size_t memo_hits() const { return memo_.hits(); }

  // The model at run `k`'s operating point over its measured span; `at`
  // (top-level parameter, SI value) set on top: an operating point no run has.
  Netlist netlist_of(const Model& m, int k, const Setting& at = {}) const;

  // The models simulated next extend these effects (the chosen ones, with a
  // candidate added): their runs resume from this model's where they
  // depart from it, not only from the unpatched model's.
  void anchor(const std::vector<EffectInstance>& effects);

  // Simulated signals of run `k` at its measurement times; empty if the run
  // failed (the reason kept, failures_since(), and given in `why`).
  std::vector<std::vector<double>> simulate(const Model& m, int k, const std::vector<Disturbance>& disturbances = {},
                                           const Setting& at = {}, std::string* why = nullptr);

  // Run `k` of the model kept at `times` (run/run.hpp: Resumption), for
  // simulate_from; null if it failed (the reason in `why`). Its signals:
  // signals_of().
  std::shared_ptr<const RunResult> keep(const Model& m, int k, const std::vector<double>& times,
                                        std::string* why = nullptr);
  // Signals of run `k` with disturbances that are zero up to the kept run's
  // checkpoint j, resumed there: its rows before it are the kept run's (a
  // run from the start when the kept run did not get that far).
  std::vector<std::vector<double>> simulate_from(const Model& m, int k, const RunResult& kept, std::size_t j,
                                                 const std::vector<Disturbance>& disturbances, std::string* why);
  // A run's table as signals at run k's measurement times, through the
  // model's measurement (lag, offset, gain); empty if the run failed.
  std::vector<std::vector<double>> signals_of(const Model& m, int k, const RunResult& res, std::string* why);

  Layout layout(Role role) const;

  // Normalised residuals (measured - simulated)/sigma for several models at
  // once (runs in parallel); a failed run's are kFailedResidual.
  std::vector<std::vector<double>> residuals(const std::vector<Model>& models, const Layout& L);

  GapTable gaps(const std::vector<double>& r, const Layout& L) const;

  struct Significance {
    double lr = 0, n_eff = 0, delta_bic = 0, p = 1;
  };
  // Likelihood ratio of model 1 over model 0 after whitening both residual
  // series with the AR(p) model of model 1's (each signal of each run its
  // own series), less a BIC penalty per added parameter.
  Significance significance(const std::vector<double>& r0, const std::vector<double>& r1, const Layout& L,
                            int added_parameters) const;
  // Vuong's statistic of model 0 against model 1 (not nested in each other)
  // on L's series, each whitened as in significance(): above about 2, model
  // 0 fits significantly better.
  double preference(const std::vector<double>& r0, const std::vector<double>& r1, const Layout& L) const;

  struct Fit {
    std::vector<EffectInstance> effects;
    std::vector<double> r_cal;
    int evaluations = 0;
  };
  // The effects' parameters fitted on the calibration layout from `start`
  // (framework/fit/bounded_lm.hpp, scaled between each parameter's bounds);
  // `r_start_hint`: the residuals at the start, if known. With
  // `grid_start`, a coarse grid over the last effect's parameters (the
  // others held at their start values) may replace the start.
  Fit fit(std::vector<EffectInstance> start, const Layout& cal, const std::vector<double>& r_start_hint,
          int max_iterations, bool grid_start = false);

  // What a screen linearises: the residuals on layout `L` at `at`, and
  // their forward differences along its parameters from the `first` on,
  // in fit()'s scaled coordinates and with its steps.
  struct Linearisation {
    std::vector<double> r;
    Eigen::MatrixXd J;
  };
  Linearisation linearise(const std::vector<EffectInstance>& at, const Layout& L, int first = 0);

  // What the unpatched model's run at each operating point tells the
  // phases (framework/diagnose/phases.hpp): its events' first times and
  // its metrics' values.
  void compute_phases(const std::vector<PhaseDecl>& declared);

  // The phase of each sample of run `k`'s span at the operating point `at`
  // (one more run of the unpatched model), the measured runs' phases named
  // as they are; all -1 when that run would rename them.
  std::vector<int> phases_at(int k, const Setting& at);

  // Why runs failed, in the order noted (a failed run's residuals are
  // kFailedResidual): kept, so that what could not be judged says why.
  std::size_t failure_count() const;
  std::vector<std::string> failures_since(std::size_t mark) const;

 private:
  PhaseStarts phase_starts(int k, const Setting& at);
  std::optional<RunResult> run(const Model& m, int k, const std::vector<Disturbance>& disturbances, const Setting& at,
                               const Resumption& resumption, std::string* why, long max_total_steps = 0);
  void note_failure(const std::string& run, const std::string& why);
  // Model m's circuit at run k (its netlist `nl`), assembled once and
  // shared by the threads, each run with an Evaluator of its own: the
  // disturbed runs of one model - the unexplained search's, many a run -
  // need no assembly of their own. Null when the model has no memo key
  // (nothing names it) or the circuit has independent parts (run_circuit
  // splits those).
  std::shared_ptr<const System> assembled(const Model& m, int k, const Netlist& nl, const SolverOptions& so);
  // A model's run k kept at the run's measurement times (in passing), with
  // its System and its memo key; null when it failed or the circuit has
  // independent parts. Resumed from `from`'s run where it departs from it
  // (departure.hpp), as its runs in the memo are.
  struct Kept {
    std::shared_ptr<const System> system;
    std::shared_ptr<const RunResult> run;
    std::string key;
  };
  Kept keep_resumed(const Model& m, int k, const Kept& from);
  // Model m's run k: its System (null: not shareable), its solver options
  // and the last checkpoint of `from`'s run before it departs from it (-1:
  // none, or no run to depart from). Throws what assembling it throws.
  struct Departure {
    std::shared_ptr<const System> system;
    SolverOptions options;
    long checkpoint = -1;
  };
  Departure departure(const Model& m, int k, const Kept& from);
  // The kept run model m's run k resumes from: the anchor's (anchor()) when
  // m extends it, else the unpatched model's. Each taken once.
  Kept kept_for(const Model& m, int k);
  // Where every undisturbed run k is kept: the run's measurement times, at
  // most kKeptCheckpoints of them.
  std::vector<double> stops(int k) const;
  // Model m's run k resumed from the kept run it extends at the last
  // checkpoint before m departs from it - the kept model's own run is the
  // kept one; nullopt when m departs at the start or cannot resume.
  std::optional<RunResult> run_resumed(const Model& m, int k, std::string* why);

  pneumo::Model loaded_;  // the model file with its plugins
  DiagnoseOptions options_;
  mutable std::mutex failures_mutex_;
  std::vector<std::string> failures_;
  std::vector<Probe> base_probes_;
  std::vector<PhaseDecl> declared_phases_;
  std::vector<PhaseStarts> phase_starts_;  // per measured run
  std::set<const Effect*> vanishing_;       // learn_nulls()
  SignalMemo memo_{kMemoValues};
  std::mutex assembled_mutex_;
  std::map<std::string, std::shared_ptr<const System>> assembled_;  // by memo key @ run; null: not shareable
  std::mutex kept_mutex_;
  std::map<int, Kept> unpatched_kept_, anchor_kept_;  // by run
  Model anchor_;  // memo_key "" when none (anchor())
};

}  // namespace pneumo::diagnose::engine
