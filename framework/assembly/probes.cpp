// Probes: outputs, integrands and observables read at a point, by
// component, through the same gathered locals the residual uses.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "framework/assembly/blocks.hpp"
#include "framework/assembly/evaluator.hpp"

namespace pneumo {

void System::poisoned_locals(const Block& b, int pass, std::mt19937& rng, bool nan_explicit, bool nan_yp, double* ly,
                             double* lyp) const {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < b.vars.size(); ++i) {
    const int v = b.vars[i];
    const double y0 = v >= 0 ? b.scale[i] * plan_.m_start[v] * (1.0 + 0.01 * pass * u(rng)) : b.offset[i];
    ly[i] = nan_explicit && v >= 0 && plan_.of_m[v] >= 0 ? nan : y0;
    lyp[i] = nan_yp ? nan : 0.0;
  }
}

namespace {

// A local-variable probe's value from the unknowns the blocks read.
double local_value(const Block& b, const Probe& p, const double* y) {
  const int g = b.vars[p.index];
  return g >= 0 ? b.scale[p.index] * y[g] : b.offset[p.index];
}

}  // namespace

double Evaluator::probe(const Probe& p, double t, const double* y, const double* yp) const {
  block_inputs(t, y, yp);
  const Block& b = *s_.blocks_[p.component];  // component blocks come first, in order
  if (p.kind == Probe::Kind::local) return local_value(b, p, y);
  double ly[kMaxLocal], lyp[kMaxLocal];
  gather(b, y, yp, ly, lyp);
  bool invalid = false;
  Eval<double> e(*b.component, t, ly, lyp, modes_.data() + b.mode0, b.connected.get(), s_.circuit_.gas, &invalid);
  return b.component->observe(p.index, e);
}

std::vector<int> System::components_reading(int i) const {
  const int m = plan_.ida_to_m[i];
  std::vector<int> out;
  for (const auto& b : blocks_)
    if (b->component_index >= 0 && std::find(b->vars.begin(), b->vars.end(), m) != b->vars.end())
      out.push_back(b->component_index);
  return out;
}

bool System::holds_constant(int component, int local) const {
  return blocks_[component]->vars[local] < 0;  // component blocks come first, in order
}

ProbeSet System::probe_set(const std::vector<Probe>& probes) const {
  ProbeSet set;
  set.size = probes.size();
  std::size_t widest = 0;
  for (std::size_t i = 0; i < probes.size(); ++i) {
    const Probe& p = probes[i];
    const int slot = static_cast<int>(i);
    if (p.kind == Probe::Kind::local) {
      set.locals.push_back(p);
      set.local_slots.push_back(slot);
      continue;
    }
    auto g = std::find_if(set.groups.begin(), set.groups.end(),
                          [&](const ProbeSet::Group& x) { return x.component == p.component; });
    if (g == set.groups.end()) {
      set.groups.push_back({p.component, {}, {}});
      g = set.groups.end() - 1;
    }
    g->observables.push_back(p.index);
    g->slots.push_back(slot);
    widest = std::max(widest, g->observables.size());
  }
  set.scratch.resize(widest);
  // Which inputs the probes read: evaluated at the start values and two
  // perturbations of them, once with every explicit unknown NaN, once with
  // every y' NaN; a probe that stays finite does not read them.
  bool explicit_read = false, yp_read = false;
  for (const auto& lp : set.locals) {
    const int v = blocks_[lp.component]->vars[lp.index];
    explicit_read |= v >= 0 && plan_.of_m[v] >= 0;
  }
  std::mt19937 rng(97531);
  bool invalid = false;
  double ly[kMaxLocal], lyp[kMaxLocal];
  for (int pass = 0; pass < 3; ++pass)
    for (int poison = 0; poison < 2; ++poison)
      for (const auto& g : set.groups) {
        const Block& b = *blocks_[g.component];
        poisoned_locals(b, pass, rng, poison == 0, poison == 1, ly, lyp);
        Eval<double> e(*b.component, 0.1 * pass, ly, lyp, modes_.data() + b.mode0, b.connected.get(), circuit_.gas,
                       &invalid);
        b.component->observe_all(g.observables.data(), static_cast<int>(g.observables.size()), e,
                                 set.scratch.data());
        for (std::size_t k = 0; k < g.observables.size(); ++k)
          if (!std::isfinite(set.scratch[k])) (poison == 0 ? explicit_read : yp_read) = true;
      }
  set.reads_explicit = explicit_read && !plan_.unknowns.empty();
  set.reads_yp = yp_read;
  return set;
}

void Evaluator::probe_all(const ProbeSet& set, double t, const double* y, const double* yp, double* out) const {
  // Locals too read the inputs expanded only if some probe of the set needs
  // the explicit unknowns: a state read alone costs no explicit solve.
  block_inputs(t, y, yp, set.reads_explicit);
  for (std::size_t i = 0; i < set.locals.size(); ++i)
    out[set.local_slots[i]] = local_value(*s_.blocks_[set.locals[i].component], set.locals[i], y);
  double ly[kMaxLocal], lyp[kMaxLocal];
  bool invalid = false;
  for (const auto& g : set.groups) {
    const Block& b = *s_.blocks_[g.component];  // component blocks come first, in order
    gather(b, y, yp, ly, lyp);
    Eval<double> e(*b.component, t, ly, lyp, modes_.data() + b.mode0, b.connected.get(), s_.circuit_.gas, &invalid);
    const int n = static_cast<int>(g.observables.size());
    b.component->observe_all(g.observables.data(), n, e, set.scratch.data());
    for (int k = 0; k < n; ++k) out[g.slots[k]] = set.scratch[k];
  }
}

}  // namespace pneumo
