// A resumable integration: simulate() in pieces. A program that steps the
// circuit from outside (an FMU's doStep) starts it once, advances it to one
// communication point after another, changes its external inputs between
// them, and reads the state at the point reached. simulate() is start(),
// advance_to(t_end), finish() - the one integration path.
#pragma once

#include <memory>

#include "framework/solver/ida_solver.hpp"

namespace pneumo {

class IdaRun;

class Integration {
 public:
  // Integrates the System of `eval`, whose modes it changes (one Evaluator
  // an integration at a time). The Evaluator must outlive the Integration;
  // options and output are copied.
  Integration(Evaluator& eval, const SolverOptions& options, OutputFn output, const Quadratures* quad = nullptr);
  ~Integration();
  Integration(const Integration&) = delete;
  Integration& operator=(const Integration&) = delete;

  // Events at t_start, consistent values (a steady start), the first output.
  // These return false once the run failed: result().message says why; the
  // state stays where the failure left it.
  bool start();
  // Instead of start(): go on from a checkpoint of a run of the same System
  // (its time events after it, output rows after it, its modes and
  // integrals; consistent values and the event iteration there).
  bool resume(const Checkpoint& from);
  // Integrate to min(t, t_end): time() is then t.
  bool advance_to(double t);
  // The System's external inputs were changed at time(): a discontinuity,
  // re-initialised as after an event (consistent values, event iteration).
  bool inputs_changed();

  double time() const;
  // The physical y, y' at time() (valid until the next call).
  const double* y();
  const double* yp();
  // The state at time() (after start(), resume() or advance_to()).
  Checkpoint checkpoint();
  // Checkpoints taken as the run passes `times` (ascending), at the first
  // output row at or after each, from IDA's interpolating polynomial: no
  // stop, so the run is the one without them, step for step. The output
  // rows' y' are then interpolated too. Taken once: passed().
  void keep_in_passing(std::vector<double> times);
  std::vector<Checkpoint> passed();
  const SolverResult& result() const;
  // The statistics, warnings and outcome; once, at the end.
  SolverResult finish();

 private:
  std::unique_ptr<IdaRun> run_;
};

}  // namespace pneumo
