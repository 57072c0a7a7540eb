// Discrete modes and events: root functions, time events, and the modes a
// component's on_event() changes. After such a change the rows that give
// explicit unknowns are checked again (verify_explicit).
#include <algorithm>
#include <cstring>
#include <cmath>
#include <stdexcept>

#include "framework/assembly/blocks.hpp"
#include "framework/assembly/evaluator.hpp"

namespace pneumo {

void Evaluator::reset_modes() {
  for (const auto& b : s_.blocks_)
    if (b->component) b->component->initial_modes(modes_.data() + b->mode0);
  work_.y = s_.plan_.m_start;
  work_.yp.assign(s_.plan_.m_start.size(), 0.0);
  work_.cache_valid = false;
}

void Evaluator::restore_modes(const std::vector<double>& modes) {
  if (modes.size() != modes_.size()) throw std::invalid_argument("restore_modes: the modes of another system");
  modes_ = modes;
  work_.cache_valid = false;
}

void Evaluator::roots(double t, const double* y, const double* yp, double* g) const {
  if (s_.plan_.any_roots_read_explicit) {
    expand_part(t, y, yp, s_.plan_.root_stages);
    y = work_.y.data();
    yp = work_.yp.data();
  } else {
    block_inputs(t, y, yp, false);
  }
  bool invalid = false;
  double ly[kMaxLocal], lyp[kMaxLocal];
  for (int bi : s_.root_blocks_) {
    const Block& b = *s_.blocks_[bi];
    gather(b, y, yp, ly, lyp);
    Eval<double> e(*b.component, t, ly, lyp, modes_.data() + b.mode0, b.connected.get(), s_.circuit_.gas, &invalid);
    b.component->roots(e, g + b.root0);
  }
}

std::vector<double> System::time_events() const {
  std::vector<double> out;
  for (const auto& b : blocks_)
    if (b->component)
      for (double t : b->component->time_events()) out.push_back(t);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

namespace {

// Whether an event left a component's modes as they were, bit for bit: a
// mode that holds NaN for "none" (a valve's pending command) is unchanged
// when it still does.
bool same_modes(const std::vector<double>& before, const double* modes) {
  return before.empty() || std::memcmp(before.data(), modes, before.size() * sizeof(double)) == 0;
}

}  // namespace

// After an event changed a component's modes: the rows that give explicit
// unknowns must still give them linearly, with the same coefficient and no
// new dependencies (the plan's, explicit.cpp).
void Evaluator::verify_explicit(int block, double t) const {
  const Block& b = *s_.blocks_[block];
  const int nl = static_cast<int>(b.vars.size());
  bool invalid = false;
  EvalContext ctx = context(&invalid);
  std::vector<Pattern> pr;
  std::vector<Dual> dr;
  evaluate_structure(b, t, work_.y.data(), work_.yp.data(), ctx, pr, dr);
  for (const auto& x : s_.plan_.unknowns) {
    if (x.row < b.row0 || x.row >= b.row0 + b.n_rows) continue;
    const int k = x.row - b.row0;
    bool ok = true;
    double c = 0.0;
    for (int i = 0; i < nl; ++i) {
      const int g = b.vars[i];
      if (g < 0) continue;
      if (pr[k].deps.test(kMaxLocal + i)) ok = false;
      if (pr[k].deps.test(i) && !std::binary_search(x.deps.begin(), x.deps.end(), g)) ok = false;
      if (g == x.var) {
        if (pr[k].nonlin.test(i)) ok = false;
        c += dr[k].deriv(i);
      }
    }
    if (ok && c == x.coef) continue;
    throw std::runtime_error("equation '" + s_.equation_name(x.row) + "' of " + b.label + ", solved explicitly for '" + s_.plan_.m_names[x.var] +
                             "' at assembly, no longer gives it linearly with the same coefficient after an event "
                             "changed the component's modes; assemble with eliminate_explicit = false");
  }
}

// One component's event at (t, y, yp): its on_event() may change its
// modes; then the explicit unknowns may take other values at the same
// (t, y) - a signal source's step - and the rows that give them are checked
// again. Returns whether the modes changed.
bool Evaluator::fire_event(int bi, double t, const double* y, const double* yp, EventKind kind, int root, int dir,
                           std::vector<EventLogEntry>& log) {
  const Block& b = *s_.blocks_[bi];
  double ly[kMaxLocal], lyp[kMaxLocal];
  bool invalid = false;
  gather(b, y, yp, ly, lyp);
  double* modes = modes_.data() + b.mode0;
  Eval<double> e(*b.component, t, ly, lyp, modes, b.connected.get(), s_.circuit_.gas, &invalid);
  const std::vector<double> before(modes, modes + b.component->info().modes);
  const EventResult res = b.component->on_event(e, modes, kind, root, dir);
  if (!s_.plan_.unknowns.empty() && !same_modes(before, modes)) {
    verify_explicit(bi, t);
    work_.cache_valid = false;
  }
  if (!res.message.empty() || !res.tag.empty()) log.push_back({t, b.component->name(), res.message, res.tag});
  return res.changed;
}

std::vector<std::string> Evaluator::end_notes(double t, const double* y, const double* yp) {
  block_inputs(t, y, yp);
  std::vector<std::string> notes;
  for (const auto& block : s_.blocks_) {
    const Block& b = *block;
    if (!b.component) continue;
    double ly[kMaxLocal], lyp[kMaxLocal];
    bool invalid = false;
    gather(b, y, yp, ly, lyp);
    const double* modes = modes_.data() + b.mode0;
    const Eval<double> e(*b.component, t, ly, lyp, modes, b.connected.get(), s_.circuit_.gas, &invalid);
    if (std::string note = b.component->at_end(e, modes); !note.empty())
      notes.push_back(b.component->name() + ": " + note);
  }
  return notes;
}

std::vector<ExternalInput> System::external_inputs() const {
  std::vector<ExternalInput> out;
  for (const auto& b : blocks_)
    if (b->component)
      for (const auto& spec : b->component->external_inputs())
        out.push_back({b->component->name(), spec, b->mode0 + spec.mode});
  return out;
}

void Evaluator::set_external_input(std::size_t k, double value) {
  const std::vector<ExternalInput> inputs = s_.external_inputs();
  if (k >= inputs.size()) throw std::out_of_range("no external input " + std::to_string(k));
  modes_[inputs[k].mode] = value;
  work_.cache_valid = false;
}

bool Evaluator::handle_time_event(double t, const double* y, const double* yp, std::vector<EventLogEntry>& log) {
  block_inputs(t, y, yp);
  bool changed = false;
  for (std::size_t bi = 0; bi < s_.blocks_.size(); ++bi) {
    const Block& b = *s_.blocks_[bi];
    if (!b.component) continue;
    bool due = false;
    for (double te : b.component->time_events()) due |= std::abs(te - t) <= 1e-12 * std::max(1.0, std::abs(t));
    if (due) changed |= fire_event(static_cast<int>(bi), t, y, yp, EventKind::time, -1, 0, log);
  }
  return changed;
}

bool Evaluator::handle_roots(double t, const double* y, const double* yp, const int* root_info,
                             std::vector<EventLogEntry>& log) {
  block_inputs(t, y, yp);
  bool changed = false;
  for (std::size_t bi = 0; bi < s_.blocks_.size(); ++bi) {
    const Block& b = *s_.blocks_[bi];
    if (!b.component) continue;
    for (int k = 0; k < b.component->info().roots; ++k) {
      const int dir = root_info[b.root0 + k];
      if (dir != 0) changed |= fire_event(static_cast<int>(bi), t, y, yp, EventKind::root, k, dir, log);
    }
  }
  return changed;
}

bool Evaluator::handle_input_changes(double t, const double* y, const double* yp, std::vector<EventLogEntry>& log,
                                     std::vector<std::string>* changed) {
  block_inputs(t, y, yp);
  bool any = false, invalid = false;
  double ly[kMaxLocal], lyp[kMaxLocal];
  for (std::size_t bi = 0; bi < s_.blocks_.size(); ++bi) {
    const Block& b = *s_.blocks_[bi];
    if (!b.component || !b.component->info().follows_inputs) continue;
    gather(b, y, yp, ly, lyp);
    double* modes = modes_.data() + b.mode0;
    Eval<double> e(*b.component, t, ly, lyp, modes, b.connected.get(), s_.circuit_.gas, &invalid);
    const std::vector<double> before(modes, modes + b.component->info().modes);
    const EventResult res = b.component->on_inputs_changed(e, modes);
    if (!s_.plan_.unknowns.empty() && !same_modes(before, modes)) {
      verify_explicit(static_cast<int>(bi), t);
      work_.cache_valid = false;
    }
    if (res.changed && changed) changed->push_back(b.component->name());
    any |= res.changed;
    if (!res.message.empty() || !res.tag.empty()) log.push_back({t, b.component->name(), res.message, res.tag});
  }
  return any;
}

}  // namespace pneumo
