// pneumo fit friction DATA.csv --model eq4|eq7|eq8 [--pressure pAB-|pAB+|pEC] [--offset] [-o preset.yaml]
// pneumo fit throttle DATA.csv [-o throttle.yaml]
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include "framework/cli/command.hpp"
#include "framework/core/text.hpp"
#include "framework/io/files.hpp"
#include "components/fit/friction_fit.hpp"
#include "framework/fit/throttle_fit.hpp"

namespace pneumo::cli {

namespace {

using namespace pneumo::fit;

// A named output is checked before any work: not the data file, a directory,
// a device or a link.
void check_output(const std::string& output, const std::string& data) {
  if (!output.empty()) check_output_file(output, "-o", {data});
}

std::string bar_rel(double p_abs, double p_amb) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", (p_abs - p_amb) / 1e5);
  return buf;
}

// Data a least-squares fit can say something about: every value finite
// (an overflowing 1e400 is read as infinity), and at least one of the
// columns in `varying` not constant (`why` says why it must vary): a fit of
// constant data "succeeds" with meaningless coefficients.
void check_fit_data(const DataTable& d, const std::vector<std::string>& varying, const std::string& why) {
  for (std::size_t i = 0; i < d.rows.size(); ++i)
    for (std::size_t c = 0; c < d.rows[i].size() && c < d.names.size(); ++c)
      if (!std::isfinite(d.rows[i][c]))
        throw InputError(d.where(i), "", d.names[c],
                         "column '" + d.names[c] + "': the value is not a finite number (too large, inf or nan)");
  std::string present;
  for (const auto& name : varying) {
    const int c = d.column(name);
    if (c < 0) continue;
    for (const auto& row : d.rows)
      if (row[c] != d.rows.front()[c]) return;
    present += (present.empty() ? "'" : " and '") + name + "'";
  }
  if (!present.empty())
    throw InputError(SourceLocation{d.file, d.header_line, 1}, "", "",
                     present + " has the same value in every row: " + why);
}

// A fit whose sums of squares or coefficients overflowed says nothing.
void check_fit_result(const FitReport& r, const std::string& file) {
  bool finite = std::isfinite(r.rss) && std::isfinite(r.tss) && std::isfinite(r.r2);
  for (const auto& p : r.parameters) finite = finite && std::isfinite(p.value);
  if (!finite)
    throw InputError(SourceLocation{file, 0, 0}, "", "",
                     "the fit overflowed (its sums of squares or coefficients are not finite numbers): the data hold "
                     "values too large for a measurement; check their units");
}

std::string rms_text(double N) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", N);
  return buf;
}

class FitCommand {
 public:
  explicit FitCommand(CLI::App& app) {
    fit_ = app.add_subcommand("fit", "identify friction or throttle coefficients from measured data (Ceres)");
    fit_->require_subcommand(1);
    fric_ = fit_->add_subcommand(
        "friction", "fit paper [1] eq. 4/7/8 to (v, p_A, p_B, F) or (v, p_EC, F) or (v, [p0,] F) points");
    fric_->add_option("data", data_, "CSV with a header; columns v, F, p_A, p_B / p_EC / p0; units in brackets")
        ->required();
    fric_->add_option("--model", model_, "eq4, eq7 or eq8")->required()->check(CLI::IsMember({"eq4", "eq7", "eq8"}));
    fric_->add_option("--pressure", pressure_, "pressure of eq. 4/8: pAB- (default), pAB+ or pEC")
        ->check(CLI::IsMember({"pAB-", "pAB+", "pEC"}));
    fric_->add_option("--init", init_, "initial value NAME=VALUE (paper units)")->take_all();
    fric_->add_option("--lower", lower_, "lower bound NAME=VALUE")->take_all();
    fric_->add_option("--upper", upper_, "upper bound NAME=VALUE")->take_all();
    fric_->add_option("--fix", fix_, "hold NAME at VALUE")->take_all();
    fric_->add_flag("--offset", offset_,
                    "also fit a constant force offset F0 (a load cell's zero): F signed, positive along v, "
                    "F = sign(v) law + F0");
    fric_->add_option("--validate", validate_,
                      "data files (same columns) the fitted law is checked on: RMS force error in N on each, e.g. "
                      "another supply pressure or a held-out run")
        ->take_all();
    fric_->add_option("-o,--output", output_, "write the netlist-ready friction preset (YAML) here");

    thr_ = fit_->add_subcommand("throttle",
                                "fit ISO 6358 C and b to (p1, p2, T1, m_flow) points; with a column z, C(z) and b(C)");
    thr_->add_option("data", tdata_, "CSV with a header; columns p1, p2, m_flow, optional T1 [K] and z [rev]")
        ->required();
    thr_->add_option("-o,--output", toutput_, "write the netlist-ready parameters (YAML) here");
  }

  CLI::App* app() const { return fit_; }
  int run() { return fric_->parsed() ? run_friction() : run_throttle(); }

 private:
  InputError data_error(const std::string& file, const std::string& msg) const {
    return InputError(SourceLocation{file, 0, 0}, "", "", msg);
  }

  int run_friction() {
    const FrictionModel m = parse_friction_model(model_);
    const auto pressure = m == FrictionModel::eq7 ? components::FrictionPressure::none
                                                  : parse_friction_pressure(pressure_.empty() ? "pAB-" : pressure_);
    if (m == FrictionModel::eq7 && !pressure_.empty())
      throw data_error(data_, "--pressure: eq. 7 has no pressure term (it is fitted per supply pressure p0)");
    auto params = default_friction_parameters(m, offset_);
    try {
      for (const auto& s : init_) set_parameter(params, s, ParameterField::initial);
      for (const auto& s : lower_) set_parameter(params, s, ParameterField::lower);
      for (const auto& s : upper_) set_parameter(params, s, ParameterField::upper);
      for (const auto& s : fix_) set_parameter(params, s, ParameterField::fixed);
      check_parameters(params);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("fit friction: ") + e.what());
    }
    check_output(output_, data_);
    const DataTable d = read_data_table(data_);
    check_fit_data(d, {"v"}, "a fit needs friction measured at several speeds");
    check_fit_data(d, {"F"}, "a constant force leaves nothing to fit (R2 is undefined)");
    const auto points = friction_points(d, pressure);
    std::vector<std::vector<FrictionPoint>> held_out;  // read before the fit: bad input stops it
    for (const auto& file : validate_) {
      check_output(output_, file);
      held_out.push_back(friction_points(read_data_table(file), pressure));
      if (held_out.back().empty())
        throw data_error(file, "--validate: the file holds no friction points (rows with v != 0): nothing to check "
                               "the fitted law on");
    }
    const std::string cmd = "pneumo fit friction " + one_line(data_) + " --model " + model_ +
                            (pressure == components::FrictionPressure::none ? "" : " --pressure " +
                                                                                      friction_pressure_name(pressure));
    // Eq. 7 with a p0 column: one fit per supply pressure, as Annex B.
    std::vector<std::pair<double, std::vector<FrictionPoint>>> groups;  // p0 (NaN: all points)
    const int cp0 = d.column("p0");
    if (m == FrictionModel::eq7 && cp0 >= 0) {
      std::map<double, std::vector<FrictionPoint>> by_p0;
      for (std::size_t i = 0; i < points.size(); ++i) by_p0[d.rows[i][cp0]].push_back(points[i]);
      groups.assign(by_p0.begin(), by_p0.end());
    } else {
      groups.emplace_back(NAN, points);
    }
    if (groups.size() > 1 && !validate_.empty())
      throw data_error(data_, "--validate: eq. 7 with a p0 column is fitted per supply pressure; validate one "
                              "pressure's fit at a time (a file without p0)");
    std::ostringstream yaml;
    bool all_converged = true;
    for (const auto& [p0, pts] : groups) {
      FitReport r;
      try {
        r = fit_friction(m, pts, params);
        check_fit_result(r, data_);
      } catch (const std::invalid_argument& e) {
        throw data_error(data_, std::string(e.what()) + (std::isnan(p0) ? "" : " at p0 = " + bar_rel(p0, 101325) +
                                                                                   " bar_rel"));
      }
      all_converged = all_converged && r.converged;
      std::cout << "friction " << model_ << (std::isnan(p0) ? "" : " at p0 = " + bar_rel(p0, 101325) + " bar_rel")
                << (pressure == components::FrictionPressure::none
                        ? ""
                        : ", p = " + friction_pressure_name(pressure) + " in bar")
                << ":\n"
                << format_report(r, "N^2");
      const auto c = friction_coefficients(m, r, pressure);
      std::string header = cmd;
      if (!std::isnan(p0)) {
        header += "\nsupply pressure p0 = " + bar_rel(p0, 101325) + " bar_rel";
        yaml << (yaml.tellp() > 0 ? "---\n" : "");
      }
      if (offset_)
        header += "\nforce offset F0 = " + std::to_string(r.value("F0")) + " N (+- " +
                  std::to_string(r.parameter("F0").std_error) + "): the sensor's, not the seal's";
      yaml << friction_preset_yaml(c, r, m, pressure == components::FrictionPressure::ec, header);
      print_rms(m, r, pts, held_out);
    }
    if (!output_.empty()) {
      write_text_atomic(output_, yaml.str());
      std::cout << "wrote the friction preset to " << output_ << "\n";
    }
    if (!all_converged) std::cerr << "pneumo: the fit did not converge (see above)\n";
    return all_converged ? 0 : 1;
  }

  // The law's RMS force error on its own points and on each --validate file.
  void print_rms(FrictionModel m, const FitReport& r, const std::vector<FrictionPoint>& own,
                 const std::vector<std::vector<FrictionPoint>>& held_out) const {
    std::cout << "RMS force error: " << rms_text(friction_rms(m, r, own)) << " N on the " << own.size()
              << " fitted points\n";
    for (std::size_t i = 0; i < held_out.size(); ++i)
      std::cout << "  " << rms_text(friction_rms(m, r, held_out[i])) << " N on " << validate_[i] << " ("
                << held_out[i].size() << " points)\n";
  }

  int run_throttle() {
    check_output(toutput_, tdata_);
    const DataTable d = read_data_table(tdata_);
    check_fit_data(d, {"p1", "p2"}, "a fit needs flows measured at several pressure ratios");
    check_fit_data(d, {"m_flow"}, "a constant flow leaves nothing to fit (R2 is undefined)");
    bool has_z = false;
    const auto pts = throttle_points(d, &has_z);
    const std::string header = "pneumo fit throttle " + one_line(tdata_);
    std::string yaml;
    bool ok = true;
    try {
      if (has_z) {
        const NeedleFit f = fit_needle_throttle(pts);
        for (const auto& r : f.per_opening) check_fit_result(r, tdata_);
        for (std::size_t i = 0; i < f.z.size(); ++i) {
          std::cout << "opening z = " << f.z[i] << " rev:\n" << format_report(f.per_opening[i], "(kg/s)^2");
          ok = ok && f.per_opening[i].converged;
        }
        std::cout << "b(C) = " << f.b0 << " + " << f.b_slope << " C/C_max, C_max = " << f.C_max
                  << " dm3/(s*bar), R2 of the line " << f.b_line_r2 << "\n";
        yaml = needle_throttle_yaml(f, header);
      } else {
        const FitReport r = fit_throttle(pts);
        check_fit_result(r, tdata_);
        std::cout << "ISO 6358 throttle:\n" << format_report(r, "(kg/s)^2");
        ok = r.converged;
        yaml = throttle_yaml(r, header);
      }
    } catch (const std::invalid_argument& e) {
      throw data_error(tdata_, e.what());
    }
    if (!toutput_.empty()) {
      write_text_atomic(toutput_, yaml);
      std::cout << "wrote the throttle parameters to " << toutput_ << "\n";
    }
    if (!ok) std::cerr << "pneumo: the fit did not converge (see above)\n";
    return ok ? 0 : 1;
  }

  CLI::App *fit_ = nullptr, *fric_ = nullptr, *thr_ = nullptr;
  std::string data_, model_, pressure_, output_, tdata_, toutput_;
  std::vector<std::string> init_, lower_, upper_, fix_, validate_;
  bool offset_ = false;
};

}  // namespace

Command add_fit_command(CLI::App& app) {
  auto fit = std::make_shared<FitCommand>(app);
  return {.app = fit->app(), .run = [fit] { return fit->run(); }};
}

}  // namespace pneumo::cli

