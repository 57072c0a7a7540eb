// How the diagnosis judges and orders candidate effects
// (docs/how-to/diagnose.md): significance is a gate, the rank is the share of the
// validation gap an effect explains, and "practical" is measured in noise
// units - what the measurements resolve, not what some benchmark's effects
// happen to produce.
#pragma once

#include <string>

#include "framework/diagnose/diagnose.hpp"

namespace pneumo::diagnose {

// Share of the gap in excess of the noise (gap - 1) that a model removes.
double excess_reduction(double gap_before, double gap_after);

// The model explains the data: the validation gap within `adequate_gap` on
// the whole set and on every signal - one badly fitted signal (x off by two
// noise sd while three pressures and temperatures fit) is a gap the total
// averages away, not an explained measurement.
bool explains_the_data(const GapTable& gap, const DiagnoseOptions& opt);

// Practical significance of going from `before` to `after`, judged on the
// whole set and on each signal whose own gap exceeds `adequate_gap` (one badly
// fitted signal, a lagging thermometer, can dominate the total and hide an
// effect that repairs the others): the mean square removed (noise variance =
// 1) must be at least one noise variance - the simulated signals change by at
// least the noise, RMS - and at least what a `noise_uncertainty` error of the
// noise level alone would move the mean square by, ((1 + u)^2 - 1) ms_before.
// `why`: the set that passed ("total" or a signal's name).
bool practically_significant(const GapTable& before, const GapTable& after, const DiagnoseOptions& opt,
                             std::string* why = nullptr);

// Ranks the candidates (EffectResult::rank, 1 = best; returns the indices in
// rank order): fitted before screened out; among the fitted, significant
// (the gate) before not significant, each by the share of the validation gap
// it removes - however large its likelihood ratio, an effect removing 1 % of
// the gap never ranks above one removing 85 %. Screened-out candidates follow
// by their screening improvement; unavailable ones are not ranked.
std::vector<int> rank_effects(std::vector<EffectResult>& results);

}  // namespace pneumo::diagnose
