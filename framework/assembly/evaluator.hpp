// One integration's view of an assembled System. The System is the
// structure and its reductions, never changed once built, so that several
// integrations share one: a study's threads, a diagnosis's runs of one
// model with other disturbances. What a run changes lives here: the
// discrete modes, a steady start's resting, and the scratch and cache of
// the residual and the Newton matrix (evaluator.cpp, events.cpp,
// probes.cpp).
#pragma once

#include <string>
#include <vector>

#include "framework/assembly/system.hpp"

namespace pneumo {

class Evaluator {
 public:
  // The modes at the components' initial values, not resting. The System
  // must outlive the Evaluator.
  explicit Evaluator(const System& system);

  const System& system() const { return s_; }

  // Residual; returns 0, or 1 if a component rejected the point (p <= 0, ...)
  // or a residual is not finite: IDA then retries with a smaller step.
  int residual(double t, const double* y, const double* yp, double* F) const;
  // dF/dy + cj dF/dy' into `values` (CSC order of the System's col_ptr/row_idx).
  int jacobian(double t, const double* y, const double* yp, double cj, double* values) const;
  // The two parts of that matrix (CSC order), so that jacobian(cj) =
  // dFdy + cj dFdyp for every cj: the matrix is linear in cj, F being linear
  // in y' and the explicit unknowns having no y'. Returns as jacobian().
  int newton_matrix_parts(double t, const double* y, const double* yp, double* dFdy, double* dFdyp) const;
  // dF/dy and dF/dy' separately (dense, row-major n x n), for tests.
  void jacobian_parts(double t, const double* y, const double* yp, std::vector<double>& dFdy,
                      std::vector<double>& dFdyp) const;

  // A steady start's settling (AssemblyOptions::rest_heat): unconnected
  // heat ports exchange heat with the ambient temperature while resting,
  // not otherwise. Returns false, changing nothing, if the System was
  // assembled without rest_heat.
  bool set_resting(bool resting);

  // Discrete modes and events.
  std::vector<double>& modes() { return modes_; }
  const std::vector<double>& modes() const { return modes_; }
  void reset_modes();
  // The modes a run had at one instant (a checkpoint another run resumes from).
  void restore_modes(const std::vector<double>& modes);
  void roots(double t, const double* y, const double* yp, double* g) const;
  // Apply time events due at t, or the roots flagged in root_info (IDA's
  // +1/-1/0 per root). Returns true if any mode changed.
  bool handle_time_event(double t, const double* y, const double* yp, std::vector<EventLogEntry>& log);
  bool handle_roots(double t, const double* y, const double* yp, const int* root_info,
                    std::vector<EventLogEntry>& log);
  // One pass of event iteration at consistent (y, y') after a
  // re-initialisation: every component re-reads its inputs
  // (Component::on_inputs_changed). Returns true if any mode changed; the
  // names of the components that changed go to `changed` if given.
  bool handle_input_changes(double t, const double* y, const double* yp, std::vector<EventLogEntry>& log,
                            std::vector<std::string>* changed = nullptr);
  // Input k's new value (System::external_inputs): its mode written, the
  // explicit unknowns derived again. The integration must then restart
  // (Integration::inputs_changed).
  void set_external_input(std::size_t k, double value);

  // Each component's at_end() at the run's last point, as "NAME: sentence".
  std::vector<std::string> end_notes(double t, const double* y, const double* yp);

  double probe(const Probe& p, double t, const double* y, const double* yp) const;
  // out[i] = probe(probes[i], ...) of the probes `set` was made of
  // (System::probe_set).
  void probe_all(const ProbeSet& set, double t, const double* y, const double* yp, double* out) const;

  // Number of Jacobian entries that AD found outside the structural pattern
  // (should stay 0; reported in the statistics).
  long pattern_misses() const { return work_.pattern_misses; }

 private:
  using Stage = System::Stage;

  EvalContext context(bool* invalid) const;
  // Unknowns the blocks read (after alias elimination, before explicit
  // elimination) from IDA's y: copies the states and solves the explicit
  // unknowns into work_.y/yp (cached for the last t and y). Returns true if a
  // component rejected the point.
  bool expand(double t, const double* y, const double* yp) const;
  // Only the explicit unknowns of `part` (a subset of the stages closed
  // under their dependencies) from IDA's y, the others at their start
  // values; no cache. Returns true if a component rejected the point.
  bool expand_part(double t, const double* y, const double* yp, const Stage& part) const;
  // IDA's y and y' into the m-level unknowns, the explicit ones at their
  // start values (from which expand() and expand_part() solve them).
  void load_states(const double* y, const double* yp) const;
  // One stage's blocks evaluated and their unknowns solved into work_.y.
  void solve_stage(double t, const Stage& stage, const EvalContext& ctx) const;
  // Points y and yp at the unknowns the blocks read: expanded, or with
  // `read_explicit` false the states alone (the explicit unknowns then keep
  // stale values the caller promises not to read). Unchanged without
  // explicit elimination.
  void block_inputs(double t, const double*& y, const double*& yp, bool read_explicit = true) const;
  // AD Jacobian over the alias-reduced unknowns into values (the plan's j1 pattern).
  int jacobian_blocks(double t, const double* y, const double* yp, double cj, double* values) const;
  bool fire_event(int block, double t, const double* y, const double* yp, EventKind kind, int root, int dir,
                  std::vector<EventLogEntry>& log);
  // After an event changed the modes of a component that gives explicit
  // unknowns: its rows must still give them linearly, with the same
  // coefficient and no new dependencies (throws otherwise).
  void verify_explicit(int block, double t) const;

  const System& s_;
  std::vector<double> modes_;
  // The conductance of the rest-heat rows: System::kRestHeatConductance
  // while resting, else 0.
  double rest_heat_ = 0.0;

  // The scratch and the cache of the last expansion; mutable, since
  // evaluating changes no result.
  struct Workspace {
    std::vector<double> y, yp;     // the m-level unknowns the blocks read (expand())
    std::vector<double> F_full;    // every full row's residual
    std::vector<double> j1_values, d_values, scatter;  // m-level Jacobian, d explicit / d y_IDA, one row's sums
    std::vector<double> cache_y;   // IDA's y of the last expansion, at cache_t
    double cache_t = 0.0;
    bool cache_valid = false, cache_invalid = false;
    long pattern_misses = 0;       // AD entries outside the pattern (should stay 0)
  };
  mutable Workspace work_;
};

}  // namespace pneumo
