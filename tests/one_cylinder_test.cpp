// `cushioned_cylinder` is a preset of the one double-acting cylinder
// (components/cylinder.hpp): configured the same way, `cylinder` is the
// same piston seen from the other end. A cap-cushioned stroke into the
// cap end, once through each type, agrees at every output row to 1e-9
// relative: x_cylinder = stroke - x_cushioned, the pressures equal. The
// two order their unknowns differently, so IDA's Newton iterates (converged
// to the solver's tolerance, not to rounding) differ by about that
// tolerance: the runs use 1e-12.
// And a rod-end cushioning length without the rod-end sleeve that would
// make it cushioning is an input error naming the component and the
// missing parameter.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "components/builtin.hpp"
#include "framework/assembly/system.hpp"
#include "framework/core/error.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

// Supply into the port that retracts, the cap side exhausted through a
// meter-out throttle, the load at rest extended; `cyl` the cylinder's
// definition, `drive` / `exhaust` its ports, `names` its outputs.
std::string circuit(const std::string& cyl, const std::string& drive, const std::string& exhaust,
                    const std::string& outputs) {
  return R"(
ambient: {p: 101325 Pa, T: 293.15 K}
components:
  supply:    {type: pressure_source, p: 6 bar, T: 293.15 K}
  valve:     {type: iso6358_throttle, C: 1 dm3/(s*bar), b: 0.3}
  meter_out: {type: iso6358_throttle, C: 0.35 dm3/(s*bar), b: 0.45}
  atmo:      {type: atmosphere}
  load:      {type: translational_mass, m: 2 kg}
  cyl: {)" + cyl + R"(}
connections:
  - [supply.port, valve.a]
  - [valve.b, cyl.)" + drive + R"(]
  - [cyl.)" + exhaust + R"(, meter_out.a]
  - [meter_out.b, atmo.port]
  - [cyl.flange, load.flange]
outputs:
)" + outputs + R"(
simulation: {t_end: 0.3 s, output_interval: 1 ms, rtol: 1e-12, atol: 1e-12}
)";
}

const std::string kCommon =
    "bore: 32 mm, rod: 12 mm, stroke: 100 mm, friction_model: coulomb_viscous, friction_viscous: 100 N*s/m, ";

std::string cushioned(const std::string& extra = "") {
  return "type: cushioned_cylinder, " + kCommon +
         "x0: 0 mm, plug_diameter: 16 mm, cushion_length: 20 mm, dead_volume_rod_side: 3 mL, "
         "dead_volume_cushion: 2 mL, dead_volume_channel: 1 mL, bore_opening_C: 5 dm3/(s*bar), "
         "bore_opening_b: 0.5, bore_opening_ramp: 0.5 mm, "
         "cushion_C_of_z: [[0, 0.05 dm3/(s*bar)], [1, 0.05 dm3/(s*bar)]], cushion_b0: 0.3, z_EC: 0.5, "
         "p0_A: 101325 Pa, p0_cap: 6 bar" +
         extra;
}

std::string plain_seen_from_rod_end() {
  return "type: cylinder, " + kCommon +
         "x0: 100 mm, cap_plug_diameter: 16 mm, cap_cushion_length: 20 mm, dead_volume_rod: 3 mL, "
         "cap_dead_volume_cushion: 2 mL, dead_volume_cap: 1 mL, cap_bore_opening_C: 5 dm3/(s*bar), "
         "cap_bore_opening_b: 0.5, cap_bore_opening_ramp: 0.5 mm, cap_cushion_C: 0.05 dm3/(s*bar), "
         "cap_cushion_b: 0.3, p0_rod: 101325 Pa, p0_cap: 6 bar";
}

// Within rtol of `scale` (the quantity's size, for values passing 0).
void expect_close(double a, double b, double scale, const std::string& what, double t) {
  EXPECT_LE(std::abs(a - b), 1e-9 * scale) << what << " at t = " << t << ": " << a << " vs " << b;
}

TEST(OneCylinder, CushionedCylinderIsTheCylinderSeenFromTheRodEnd) {
  const RunResult a = run_text(circuit(cushioned(), "A", "B",
                                       "  x: cyl.x\n  p_rod: cyl.p_A\n  p_cap: cyl.p_ch\n  p_cushion: cyl.p_EC\n"
                                       "  T_cushion: cyl.T_EC\n  F: cyl.F_friction"),
                               "cushioned.yaml");
  const RunResult b = run_text(circuit(plain_seen_from_rod_end(), "rod", "cap",
                                       "  x: cyl.x\n  p_rod: cyl.p_rod\n  p_cap: cyl.p_cap\n"
                                       "  p_cushion: cyl.p_cap_cushion\n  T_cushion: cyl.T_cap_cushion\n"
                                       "  F: cyl.F_friction"),
                               "cylinder.yaml");
  ASSERT_EQ(a.table.rows.size(), b.table.rows.size());
  const double stroke = 0.1;
  const auto x_a = column(a.table, "x"), x_b = column(b.table, "x"), t = column(a.table, "t");
  ASSERT_GT(x_a.back(), stroke - 0.01) << "the piston runs well into the cap-end cushioning zone (20 mm)";
  for (std::size_t i = 0; i < t.size(); ++i) {
    expect_close(x_b[i], stroke - x_a[i], stroke, "x", t[i]);
    for (const std::string p : {"p_rod", "p_cap", "p_cushion", "T_cushion"}) {
      const double va = column(a.table, p)[i], vb = column(b.table, p)[i];
      expect_close(vb, va, std::abs(va), p, t[i]);
    }
    const double Fa = column(a.table, "F")[i], Fb = column(b.table, "F")[i];
    expect_close(Fb, -Fa, 100.0, "F_friction (+x opposite)", t[i]);
  }
}

TEST(OneCylinder, RodCushionLengthWithoutSleeveIsAnInputError) {
  const std::string text = circuit(cushioned(", rod_cushion_length: 15 mm"), "A", "B", "  x: cyl.x");
  try {
    System s(elaborate(parse_netlist(text, "stray.yaml"), builtin_registry()));
    ADD_FAILURE() << "rod_cushion_length without rod_plug_diameter was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.component(), "cyl") << e.what();
    EXPECT_EQ(e.parameter(), "rod_plug_diameter") << e.what();
  }
}

}  // namespace
}  // namespace pneumo
