#include "framework/assembly/system.hpp"

#include <algorithm>
#include <map>
#include <numeric>

#include "framework/assembly/blocks.hpp"

namespace pneumo {

System::System(Circuit circuit, const AssemblyOptions& options)
    : circuit_(std::move(circuit)),
      // The reductions must see the rest-heat rows' dependence on T (with a
      // zero conductance Q = 0 would pass for a constant and be substituted).
      rest_heat_(options.rest_heat ? kRestHeatConductance : 0.0),
      rest_heat_ports_(options.rest_heat) {
  build_nodes();
  build_pattern();
  check_structure();
  if (options.eliminate_aliases) {
    eliminate_aliases();
  } else {
    aliases_.n_full = n_;
    aliases_.row_of.resize(n_);
    std::iota(aliases_.row_of.begin(), aliases_.row_of.end(), 0);
    for (auto& b : blocks_) {
      b->scale.assign(b->vars.size(), 1.0);
      b->offset.assign(b->vars.size(), 0.0);
    }
  }
  build_slots();
  plan_.m = n_;
  plan_.j1_col_ptr = col_ptr_;
  plan_.j1_row_idx = row_idx_;
  plan_.ida_row_of_full = aliases_.row_of;
  plan_.ida_to_m.resize(n_);
  std::iota(plan_.ida_to_m.begin(), plan_.ida_to_m.end(), 0);
  plan_.m_to_ida = plan_.ida_to_m;
  plan_.of_m.assign(n_, -1);
  plan_.m_start = start_value_;
  if (options.eliminate_aliases && options.eliminate_explicit) eliminate_explicit();
  if (plan_.unknowns.empty())
    for (std::size_t bi = 0; bi < blocks_.size(); ++bi)
      if (!blocks_[bi]->all_eliminated) plan_.final_blocks.push_back(static_cast<int>(bi));
  // Row maps of the residual's hot loop: IDA's rows, and the substituted
  // rows of blocks that are evaluated (the others are never written).
  for (int r = 0; r < aliases_.n_full; ++r)
    if (plan_.ida_row_of_full[r] >= 0) plan_.kept_full_rows.push_back({r, plan_.ida_row_of_full[r]});
  std::vector<char> evaluated(blocks_.size(), 0);
  for (int bi : plan_.final_blocks) evaluated[bi] = 1;
  for (const auto& stage : plan_.stages)
    for (const auto& entry : stage) evaluated[entry.first] = 1;
  for (std::size_t e = 0; e < aliases_.eliminated.size(); ++e)
    for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
      const Block& b = *blocks_[bi];
      if (evaluated[bi] && aliases_.eliminated[e] >= b.row0 && aliases_.eliminated[e] < b.row0 + b.n_rows)
        aliases_.checked.push_back(static_cast<int>(e));
    }
}

void System::build_slots() {
  for (auto& b : blocks_) {
    b->mapped.clear();
    b->constants.clear();
    for (std::size_t i = 0; i < b->vars.size(); ++i) {
      if (b->vars[i] >= 0) b->mapped.push_back({static_cast<int>(i), b->vars[i], b->scale[i]});
      else b->constants.push_back({static_cast<int>(i), b->offset[i]});
    }
    b->all_eliminated = true;
    for (int k = 0; k < b->n_rows; ++k) b->all_eliminated &= aliases_.row_of[b->row0 + k] < 0;
    const int nl = static_cast<int>(b->vars.size());
    b->slot.assign(nl, -1);
    b->slot_local.clear();
    // Differential unknowns take the first directions: a Dual carries as
    // many derivatives as its highest direction, and a component's costly
    // part (a cylinder's flows and friction from its positions, masses and
    // energies) usually depends on its states alone.
    std::vector<int> order(nl);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int c) {
      auto rank = [&](int i) { return b->vars[i] >= 0 && id_[b->vars[i]] != 0.0 ? 0 : 1; };
      return rank(a) < rank(c);
    });
    std::map<int, int> seen;
    for (int i : order) {
      if (b->vars[i] < 0) continue;
      auto [it, fresh] = seen.emplace(b->vars[i], static_cast<int>(b->slot_local.size()));
      if (fresh) b->slot_local.push_back(i);
      b->slot[i] = it->second;
    }
  }
}

int System::stream_mixing_rows() const {
  int rows = 0;
  for (const auto& [r, q] : plan_.kept_full_rows)
    for (const auto& b : blocks_)
      if (r >= b->row0 && r < b->row0 + b->n_rows && (is_stream_mix(*b) || is_stream_sum(*b))) ++rows;
  return rows;
}

System::~System() = default;

}  // namespace pneumo
