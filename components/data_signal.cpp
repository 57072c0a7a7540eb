// A measured column replayed as a signal: a lab data file read as it comes
// (framework/io/data_file.hpp: separator, header, skipped rows, decimal and
// thousands marks, units with a linear scale), linearly interpolated in time
// and held at its end values outside the measured span. Output 'y' is the
// value in SI, 'dy' its slope (the segment's difference quotient), e.g. the
// velocity feed-forward of a position_source replaying a measured position.
// No time event per sample: a 100 Hz file would stop the integrator every
// 10 ms; the corners are left to its error control.
#include <algorithm>

#include "components/builtin.hpp"
#include "framework/io/data_file.hpp"

namespace pneumo::components {

class DataSignal final : public ComponentT<DataSignal> {
 public:
  enum Port { kY, kDy };
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "data_signal";
    i.description =
        "Plays column 'column' of a measured data file against its time column, linearly interpolated and held at "
        "the end values: y in SI (the file's unit converted), dy its slope per second. The file is read as it "
        "comes: separator, header yes/no, skip_rows, decimal and thousands marks; scale and offset turn a raw "
        "sensor voltage into 'unit'; median and average (a running median, then a running line) remove a "
        "sensor's spikes and jitter. A relative file name is taken from the working directory.";
    i.parameters = {
        ParameterSpec::text("file", {}, "the data file (a relative name: from the netlist's folder)", std::nullopt).path(),
        ParameterSpec::text("separator", {"comma", "semicolon", "tab", "whitespace"}, "cell separator", "comma"),
        ParameterSpec::text("header", {"yes", "no"}, "the first row read names the columns", "yes"),
        ParameterSpec::scalar("skip_rows", "1", "lines dropped at the top of the file", 0.0).non_negative(),
        ParameterSpec::text("decimal", {".", ","}, "decimal mark", "."),
        ParameterSpec::text("thousands", {"none", ".", ",", "'", " "},
                            "thousands separator (equal to the decimal mark: the last mark is the decimal one)",
                            "none"),
        ParameterSpec::text("time_column", {}, "time column: its number (1 = first) or header name", "1"),
        ParameterSpec::text("time_unit", {}, "unit of the time column (s, ms, ...)", "s"),
        ParameterSpec::text("column", {}, "the replayed column: its number (1 = first) or header name",
                            std::nullopt),
        ParameterSpec::text("unit", {}, "unit of the replayed column after scale and offset ('' = SI)", ""),
        ParameterSpec::scalar("scale", "1", "the file's number is multiplied by this (e.g. N/V)", 1.0),
        ParameterSpec::scalar("offset", "1", "then this is added, in 'unit'", 0.0),
        ParameterSpec::scalar("median", "1",
                              "running median over this many samples (odd; 1 = as measured): removes spikes of up "
                              "to (median - 1)/2 samples and keeps monotone stretches exactly",
                              1.0)
            .positive(),
        ParameterSpec::scalar("average", "1",
                              "then the straight line through this many samples about each (odd; 1 = none; the "
                              "moving average of evenly logged samples): smooths a reading's jitter, keeps ramps",
                              1.0)
            .positive(),
        ParameterSpec::scalar("t_shift", "s", "the file's time minus this is the simulation's time", 0.0),
    };
    i.ports = {{"y", Domain::signal, Causality::output, "the measured value, SI"},
               {"dy", Domain::signal, Causality::output, "its slope, SI per second", true}};
    i.equations = {"replayed value", "replayed slope"};
    // The replayed rows look constant wherever the samples are (a slope
    // between two samples, a held end): one discrete mode, never switched,
    // keeps the assembly from substituting them as constants.
    i.modes = 1;
    return i;
  }

  explicit DataSignal(const Construction& c) : ComponentT(c) {
    DataFileSpec spec;
    spec.file = c.params.text("file");
    spec.separator = parse_data_separator(c.params.text("separator"));
    spec.header = c.params.text("header") == "yes";
    spec.skip_rows = static_cast<int>(c.params["skip_rows"]);
    spec.decimal = c.params.text("decimal")[0];
    spec.thousands = parse_number_mark(c.params.text("thousands"), true);
    spec.columns = {column_spec("t", c.params.text("time_column"), c.params.text("time_unit"), 1.0, 0.0),
                    column_spec("y", c.params.text("column"), c.params.text("unit"), c.params["scale"],
                                c.params["offset"])};
    for (const char* k : {"median", "average"})
      if (const std::string why = window_problem(c.params[k]); !why.empty()) throw ParameterError(k, why);
    spec.columns[1].median = static_cast<int>(c.params["median"]);
    spec.columns[1].average = static_cast<int>(c.params["average"]);
    const DataColumns d = read_data_file(spec);
    t_ = d.values[0];
    y_ = d.values[1];
    for (auto& t : t_) t -= c.params["t_shift"];
    for (std::size_t i = 1; i < t_.size(); ++i)
      if (!(t_[i] > t_[i - 1]))
        throw ParameterError("time_column", spec.file + ":" + std::to_string(d.lines[i]) +
                                                ": time must increase strictly (check time_column and thousands)");
    if (t_.size() < 2) throw ParameterError("file", spec.file + ": at least two samples are needed");
  }

  void initial_modes(double* modes) const override { modes[0] = 0.0; }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const std::size_t k = segment(e.t());
    const double slope = (y_[k + 1] - y_[k]) / (t_[k + 1] - t_[k]);
    const double tc = std::clamp(e.t(), t_.front(), t_.back());
    r[0] = e.signal(kY) - (y_[k] + slope * (tc - t_[k]));
    r[1] = e.signal(kDy) - (e.t() < t_.front() || e.t() > t_.back() ? 0.0 : slope);
  }

 private:
  static DataColumnSpec column_spec(const std::string& name, const std::string& which, const std::string& unit,
                                    double scale, double offset) {
    DataColumnSpec s{name, 0, "", unit, scale, offset};
    if (!which.empty() && std::all_of(which.begin(), which.end(), [](char ch) { return ch >= '0' && ch <= '9'; }))
      s.number = std::stoi(which);
    else
      s.header_name = which;
    return s;
  }
  // The segment [t_k, t_k+1] holding t (the first or last outside the span).
  std::size_t segment(double t) const {
    const auto it = std::upper_bound(t_.begin(), t_.end(), t);
    const std::size_t k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - t_.begin(), 1)) - 1;
    return std::min(k, t_.size() - 2);
  }

  std::vector<double> t_, y_;
};

void register_data_signal(Registry& r) { r.add<DataSignal>(); }

}  // namespace pneumo::components
