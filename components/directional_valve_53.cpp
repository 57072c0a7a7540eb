// 5/3 directional valve, spring-centred, with the solenoids 14 and 12 of
// ISO 5599: spool +1 (14) P -> A and B -> R, spool -1 (12) P -> B and
// A -> R, spool 0 the centre position - closed (all ports blocked),
// exhausted (A -> R, B -> R, P blocked) or pressurised (P -> A, P -> B, R
// blocked). Both exhausts are joined in R, as in directional_valve_52.
// The spool follows a schedule of states -1 / 0 / 1 (time events) or the
// signals command_14 and command_12 (0/1 each; the spool goes to
// command_14 - command_12, so neither or both energised centre it), at the
// spool drive's linear rate (valve_command.hpp): t_switch_time from the
// centre to either end, twice that from end to end.
// The spool has a positive overlap o (`overlap`, a fraction of the travel
// from the centre to an end): the 14 paths open over y in [o, 1], the 12
// paths over y in [-1, -o], the centre's paths close over |y| in [0, o],
// each with the C1 smoothstep of check_valve_flow.hpp. So no two positions'
// paths are open at once, and every open fraction is flat at y = 0, where
// the spring holds the spool (no kink at the rest position); each path is
// an ISO 6358 resistance.
#include "components/builtin.hpp"
#include "components/check_valve_flow.hpp"
#include "components/symbols.hpp"
#include "components/valve_command.hpp"

namespace pneumo::components {

class DirectionalValve53 final : public SpoolValve<DirectionalValve53> {
 public:
  enum Port { kP, kA, kB, kR, kCommand14, kCommand12 };
  enum Var { kY };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "directional_valve_53";
    i.description =
        "5/3 directional valve, spring-centred: solenoid 14 P -> A, B -> R; solenoid 12 P -> B, A -> R; centre "
        "closed, exhausted or pressurised (exhausts joined in R); ISO 6358 paths; spool from 'schedule' (-1/0/1) or "
        "the signals command_14 / command_12.";
    i.symbol = symbols::valve_53();
    i.parameters = ValvePath::parameters({"PA", "PB", "AR", "BR"});
    i.parameters.push_back(ParameterSpec::text(
        "centre", {"closed", "exhausted", "pressurised"},
        "centre position: closed (all ports blocked), exhausted (A, B -> R), pressurised (P -> A, B)", "closed"));
    i.parameters.push_back(ParameterSpec::scalar("overlap", "1",
                                                 "spool overlap: travel from the centre (as a fraction of the travel "
                                                 "to an end) over which the centre's paths close and no path opens",
                                                 0.2)
                               .open_range(0.0, 1.0));
    for (auto& p : SpoolDrive::parameters("-1 solenoid 12, 0 centre, 1 solenoid 14", -1.0))
      i.parameters.push_back(std::move(p));
    five_port_valve_info(i);
    i.ports.push_back({"command_14", Domain::signal, Causality::input, "solenoid 14 energised (1) or not (0)", true});
    i.ports.push_back({"command_12", Domain::signal, Causality::input, "solenoid 12 energised (1) or not (0)", true});
    i.variables = {{"y", "1", "spool position: -1 solenoid 12, 0 centre, 1 solenoid 14", 1.0}};
    i.modes = kModes;
    i.roots = kRoots;
    i.follows_inputs = true;  // a delayed command (a fault) follows the signals
    i.faults = SpoolDrive::faults("command_14");
    i.events = SpoolDrive::events({"12", "centre", "14"});
    i.faults.push_back(ValvePath::leakage_fault());
    i.faults.push_back(ValvePath::supply_restriction_fault());
    return i;
  }

  explicit DirectionalValve53(const Construction& c)
      : SpoolValve(c, kCommand14, kCommand12, kY,
                   {{-1.0, "P->B, A->R", "12"}, {0.0, "centre", "centre"}, {1.0, "P->A, B->R", "14"}}),
        PA_(c.params, "PA"),
        PB_(c.params, "PB"),
        AR_(c.params, "AR"),
        BR_(c.params, "BR"),
        centre_pressurised_(c.params.text("centre") == "pressurised" ? 1.0 : 0.0),
        centre_exhausted_(c.params.text("centre") == "exhausted" ? 1.0 : 0.0),
        overlap_(c.params["overlap"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto P = e.gas_port(kP), A = e.gas_port(kA), B = e.gas_port(kB), R = e.gas_port(kR);
    const GasModel& gas = e.gas();
    const T& y = e.var(kY);
    const T on14 = check_valve_opening(y, overlap_, 1.0 - overlap_);
    const T on12 = check_valve_opening(T(-y), overlap_, 1.0 - overlap_);
    const T centre = check_valve_opening(T(overlap_ - max(y, T(-y))), 0.0, overlap_);
    const T m_PA = PA_.mass_flow(P, A, T(on14 + centre_pressurised_ * centre), gas);
    const T m_PB = PB_.mass_flow(P, B, T(on12 + centre_pressurised_ * centre), gas);
    const T m_AR = AR_.mass_flow(A, R, T(on12 + centre_exhausted_ * centre), gas);
    const T m_BR = BR_.mass_flow(B, R, T(on14 + centre_exhausted_ * centre), gas);
    five_port_rows(P, A, B, R, m_PA, m_PB, m_AR, m_BR, gas, r);
    r[8] = spool_row(e);
  }

 private:
  ValvePath PA_, PB_, AR_, BR_;
  double centre_pressurised_, centre_exhausted_, overlap_;
};

void register_directional_valve_53(Registry& r) { r.add<DirectionalValve53>(); }

}  // namespace pneumo::components
