// The friction test of seed paper 000, section 3.1, simulated: the pull-in
// stroke of the 32/100 cylinder with 3.7 kg at supply pressures p0 of
// Annex B (2.07 ... 8.075 bar_rel), each with many meter-out openings, the
// true friction being the Annex B eq. 7 curve of that p0 (presets
// annexB_<p0>). From each run the quasi-static part of the main stroke is
// taken - constant speed, before the piston reaches the cushioning zone - and,
// as the paper did, the medians of p_A, p_B and v and the friction force
// from the force balance eq. (1):
//   |F_fr| = p_A A_A + p_amb A_R - p_EC (A_B - A_CP) - p_ch A_CP - m a
// (the cap side of this cylinder is the cushion annulus EC plus the plug
// column ch; p_B is p_EC, the cap chamber pressure; a from the sampled v).
#pragma once

#include <string>
#include <vector>

namespace pneumo::examples {

struct FrictionTestSupply {
  double p0_bar_rel;   // supply pressure, bar gauge
  std::string preset;  // true friction: components/friction.cpp preset
};

// The seven rows of Annex B.
std::vector<FrictionTestSupply> annex_b_supplies();

// n meter-out conductances, dm3/(s*bar), log-spaced over [C_min, C_max].
std::vector<double> meter_out_openings(int n, double C_min = 0.016, double C_max = 0.6);

struct FrictionTestPoint {
  double p0_bar_rel = 0;
  double C_MO = 0;        // dm3/(s*bar)
  double v = 0;           // m/s, median over the window
  double p_A = 0, p_B = 0;  // Pa absolute, medians
  double F = 0;           // N, median of the force-balance friction
  double F_model = 0;     // N, median of the cylinder's own F_friction (cross-check)
  double v_spread = 0;    // (max - min)/median of v over the window
  int samples = 0;        // samples in the window
  bool failed_after_window = false;  // the solver failed after the window (cushion zone, cap)
};

struct FrictionTestOptions {
  std::string netlist;  // examples/friction_test/friction_rig.yaml
  std::vector<FrictionTestSupply> supplies = annex_b_supplies();
  std::vector<double> openings = meter_out_openings(28);
  double x_begin = 0.040;  // m, window of the quasi-static part of the stroke
  double cushion_margin = 0.002;  // m, the window ends this far before the cushioning zone
  double max_v_spread = 0.2;      // (max - min)/median of v in the window above which a run is rejected
};

// Throws pneumo::InputError for a bad netlist, std::runtime_error when a run
// fails or never reaches the window.
std::vector<FrictionTestPoint> run_friction_test(const FrictionTestOptions& options);

// CSV with the columns `pneumo fit friction` reads.
void write_friction_points(const std::string& path, const std::vector<FrictionTestPoint>& points);

}  // namespace pneumo::examples
