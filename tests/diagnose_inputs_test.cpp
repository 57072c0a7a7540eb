// The diagnosis's inputs refused or converted before anything is simulated
// (issue #29): units in measured CSV headers converted to SI (gauge
// pressures with the model's ambient), a run's time span checked against
// the model's, `data:` confined to regular files inside the runs folder,
// one YAML document with unique keys in run files and catalogues, and a
// catalogue patch that breaks the circuit refused at load time. Each case is
// a small tank model and hand-written data: no simulation runs.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <sstream>
#include <thread>

#include "components/builtin.hpp"
#include "framework/diagnose/catalogue.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

const std::string kTank = R"(
parameters:
  p_supply: 6 bar
ambient: {p: 0.95 bar}
components:
  supply: {type: pressure_source, p: p_supply, T: 293.15 K}
  valve: {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.3}
  tank: {type: volume, V: 0.5 L, p0: 1 atm, T0: 293.15 K}
connections:
  - [supply.port, valve.a]
  - [valve.b, tank.port]
outputs: {p: tank.p, T: tank.T}
simulation: {t_end: 1.2 s, output_interval: 2 ms}
)";

struct Model {
  Netlist netlist;
  std::vector<Probe> probes;
};

Model tank() {
  Model m{parse_netlist(kTank, "tank.yaml"), {}};
  m.probes = elaborate(m.netlist, builtin_registry()).probes;
  return m;
}

// A CSV of 101 samples over [0, span] s: p rising from 1 to 5 bar, T 20 degC,
// with the header `header` and each row from `row(t, p, T)` (SI in).
template <class Row>
std::string csv(const std::string& header, double span, Row row) {
  std::ostringstream o;
  o.precision(17);
  o << header << "\n";
  for (int i = 0; i <= 100; ++i) {
    const double t = span * i / 100.0;
    row(o, t, 1e5 + 4e5 * (1 - std::exp(-t / 0.2)), 293.15);
    o << "\n";
  }
  return o.str();
}

std::string si_csv(double span = 1.0) {
  return csv("t,p,T", span, [](std::ostream& o, double t, double p, double T) { o << t << "," << p << "," << T; });
}

// A runs folder with a calibration run `cal` (data given) and a validation
// run `val` (SI data).
struct Runs {
  TempDir dir;
  fs::path runs() const { return dir.path() / "runs"; }
  explicit Runs(const std::string& cal_csv, const std::string& cal_yaml = "data: cal.csv\nrole: calibration\n") {
    fs::create_directories(runs());
    std::ofstream(runs() / "cal.csv") << cal_csv;
    std::ofstream(runs() / "cal.yaml") << cal_yaml;
    std::ofstream(runs() / "val.csv") << si_csv();
    std::ofstream(runs() / "val.yaml") << "data: val.csv\nrole: validation\n";
  }
  std::vector<diagnose::MeasuredRun> load() const {
    const Model m = tank();
    return diagnose::load_runs(runs().string(), m.netlist, m.probes, builtin_registry());
  }
  // The message of the InputError loading throws ("" if none).
  std::string error() const {
    try {
      (void)load();
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
};

const diagnose::MeasuredRun& run_named(const std::vector<diagnose::MeasuredRun>& runs, const std::string& name) {
  for (const auto& r : runs)
    if (r.name == name) return r;
  throw std::runtime_error("no run " + name);
}

// --- units in the CSV header ----------------------------------------------

TEST(DiagnoseInputs, HeaderUnitsAreConvertedToSi) {
  // The same samples in ms, bar and degC read as the SI file does.
  const Runs with_units(csv("t [ms], p [bar], T [degC]", 1.0, [](std::ostream& o, double t, double p, double T) {
    o << t * 1e3 << "," << p / 1e5 << "," << T - 273.15;
  }));
  const Runs si(si_csv());
  const auto runs_a = with_units.load(), runs_b = si.load();
  const auto& a = run_named(runs_a, "cal");
  const auto& b = run_named(runs_b, "cal");
  ASSERT_EQ(a.t.size(), b.t.size());
  for (std::size_t i = 0; i < a.t.size(); ++i) {
    EXPECT_NEAR(a.t[i], b.t[i], 1e-12);
    EXPECT_NEAR(a.y[0][i], b.y[0][i], 1e-9 * b.y[0][i]);
    EXPECT_NEAR(a.y[1][i], b.y[1][i], 1e-9);
  }
  EXPECT_NEAR(a.sigma[0], b.sigma[0], 1e-6 * b.sigma[0]);
}

TEST(DiagnoseInputs, GaugePressureAddsTheModelsAmbient) {
  // barg: 4 bar above the model's ambient of 0.95 bar is 4.95 bar absolute.
  const Runs r(csv("t, p [barg], T", 1.0, [](std::ostream& o, double t, double, double T) {
    o << t << "," << 4.0 << "," << T;
  }));
  const auto runs = r.load();
  const auto& cal = run_named(runs, "cal");
  EXPECT_NEAR(cal.y[0][0], 4.95e5, 1e-6);
}

TEST(DiagnoseInputs, UnknownOrMisfitUnitIsALocatedError) {
  const auto with_header = [](const std::string& header) {
    return Runs(csv(header, 1.0, [](std::ostream& o, double t, double p, double T) { o << t << "," << p << "," << T; }))
        .error();
  };
  // Unknown unit: file, line 1, the column of the cell, the column's name.
  std::string e = with_header("t,p [furlong],T");
  EXPECT_NE(e.find("cal.csv:1:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("column 'p'"), std::string::npos) << e;
  EXPECT_NE(e.find("furlong"), std::string::npos) << e;
  // A length for a pressure, a pressure for the time.
  e = with_header("t,p [mm],T");
  EXPECT_NE(e.find("cal.csv:1:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("does not fit"), std::string::npos) << e;
  e = with_header("t [bar],p,T");
  EXPECT_NE(e.find("cal.csv:1:1:"), std::string::npos) << e;
  EXPECT_NE(e.find("does not fit the model's time"), std::string::npos) << e;
  // An unclosed bracket.
  e = with_header("t,p [bar,T");
  EXPECT_NE(e.find("cal.csv:1:3:"), std::string::npos) << e;
}

// --- the data's time span against the model's --------------------------

TEST(DiagnoseInputs, RunPastTheModelsEndIsRefused) {
  // 2.4 s of data for a model that ends at 1.2 s.
  const std::string e = Runs(si_csv(2.4)).error();
  EXPECT_NE(e.find("cal.csv:"), std::string::npos) << e;
  EXPECT_NE(e.find("after the simulation"), std::string::npos) << e;
  EXPECT_NE(e.find("t_end = 1.2 s"), std::string::npos) << e;
}

TEST(DiagnoseInputs, MillisecondsWrittenAsSecondsAreRefused) {
  // A time column in ms without its unit reads as 1000 s.
  const std::string e = Runs(csv("t,p,T", 1.0, [](std::ostream& o, double t, double p, double T) {
                               o << t * 1e3 << "," << p << "," << T;
                             })).error();
  EXPECT_NE(e.find("cal.csv:"), std::string::npos) << e;
  EXPECT_NE(e.find("t [ms]"), std::string::npos) << e;
}

TEST(DiagnoseInputs, RunCoveringTooLittleOfTheModelIsRefused) {
  // 50 ms of data for a 1.2 s model (seconds written where ms were meant).
  const std::string e = Runs(si_csv(0.05)).error();
  EXPECT_NE(e.find("cal.csv:"), std::string::npos) << e;
  EXPECT_NE(e.find("less than a tenth"), std::string::npos) << e;
}

TEST(DiagnoseInputs, RunBeforeTheModelsStartIsRefused) {
  const std::string e = Runs(csv("t,p,T", 1.0, [](std::ostream& o, double t, double p, double T) {
                               o << t - 0.5 << "," << p << "," << T;
                             })).error();
  EXPECT_NE(e.find("cal.csv:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("before the simulation"), std::string::npos) << e;
}

// --- data: confined to the runs folder -----------------------------------

TEST(DiagnoseInputs, DataOutsideTheRunsFolderIsRefusedWithoutEchoingIt) {
  {
    const Runs r(si_csv(), "data: /etc/passwd\nrole: calibration\n");
    const std::string e = r.error();
    EXPECT_NE(e.find("cal.yaml:1:"), std::string::npos) << e;
    EXPECT_NE(e.find("absolute path"), std::string::npos) << e;
    EXPECT_EQ(e.find("root:"), std::string::npos) << e;
  }
  {
    // A CSV next to the runs folder, reached through '..' and through a link.
    const Runs r(si_csv(), "data: ../secret.csv\nrole: calibration\n");
    std::ofstream(r.dir.path() / "secret.csv") << "SECRET_FIRST_LINE\n";
    std::string e = r.error();
    EXPECT_NE(e.find("cal.yaml:1:"), std::string::npos) << e;
    EXPECT_NE(e.find("outside the runs folder"), std::string::npos) << e;
    EXPECT_EQ(e.find("SECRET_FIRST_LINE"), std::string::npos) << e;
    fs::create_symlink(r.dir.path() / "secret.csv", r.runs() / "link.csv");
    std::ofstream(r.runs() / "cal.yaml") << "data: link.csv\nrole: calibration\n";
    e = r.error();
    EXPECT_NE(e.find("outside the runs folder"), std::string::npos) << e;
    EXPECT_EQ(e.find("SECRET_FIRST_LINE"), std::string::npos) << e;
  }
}

TEST(DiagnoseInputs, DataThatIsAFifoIsRefusedWithoutHanging) {
  const Runs r(si_csv(), "data: pipe.csv\nrole: calibration\n");
  ASSERT_EQ(::mkfifo((r.runs() / "pipe.csv").c_str(), 0600), 0);
  // Opened for reading, a FIFO without a writer blocks forever: the load
  // runs on a thread of its own, so that the test fails instead of hanging.
  auto done = std::make_shared<std::promise<std::string>>();
  auto result = done->get_future();
  const std::string runs = r.runs().string();
  std::thread([done, runs] {
    try {
      const Model m = tank();
      (void)diagnose::load_runs(runs, m.netlist, m.probes, builtin_registry());
      done->set_value("");
    } catch (const std::exception& e) {
      done->set_value(e.what());
    }
  }).detach();
  ASSERT_EQ(result.wait_for(std::chrono::seconds(10)), std::future_status::ready) << "loading a FIFO hangs";
  const std::string e = result.get();
  EXPECT_NE(e.find("cal.yaml:1:"), std::string::npos) << e;
  EXPECT_NE(e.find("not a regular file"), std::string::npos) << e;
}

// --- one YAML document, unique keys --------------------------------------

TEST(DiagnoseInputs, RunFileWithADuplicateKeyOrSecondDocumentIsRefused) {
  std::string e = Runs(si_csv(), "data: cal.csv\nrole: calibration\nrole: validation\n").error();
  EXPECT_NE(e.find("cal.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("'role' appears twice"), std::string::npos) << e;
  e = Runs(si_csv(), "data: cal.csv\nrole: calibration\noperating_point: {p_supply: 5e5, p_supply: 6e5}\n").error();
  EXPECT_NE(e.find("cal.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("'p_supply' appears twice"), std::string::npos) << e;
  e = Runs(si_csv(), "data: cal.csv\nrole: calibration\n---\nrole: validation\n").error();
  EXPECT_NE(e.find("cal.yaml:4:"), std::string::npos) << e;
  EXPECT_NE(e.find("second YAML document"), std::string::npos) << e;
}

const std::string kLeak = R"(
  leak:
    parameters:
      C: {initial: 2.0e-10, lower: 0, upper: 5.0e-9, null: 0, unit: m3/(s*Pa)}
    add_components:
      leak_path: {type: iso6358_throttle, C: "${C}", b: 0.3}
      leak_air: {type: atmosphere}
    connect:
      - [tank.port, leak_path.a]
      - [leak_path.b, leak_air.port]
)";

std::string catalogue_error(const std::string& text) {
  TempDir dir;
  const std::string path = dir.write("catalogue.yaml", text);
  const Model m = tank();
  try {
    (void)diagnose::load_catalogue(path, m.netlist, builtin_registry());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(DiagnoseInputs, CatalogueWithADuplicateKeyOrSecondDocumentIsRefused) {
  ASSERT_EQ(catalogue_error("effects:" + kLeak), "");
  // The same effect twice: the first would be silently dropped.
  std::string e = catalogue_error("effects:" + kLeak + kLeak);
  EXPECT_NE(e.find("catalogue.yaml:12:"), std::string::npos) << e;
  EXPECT_NE(e.find("'leak' appears twice"), std::string::npos) << e;
  e = catalogue_error("effects:" + kLeak + "---\neffects: {}\n");
  EXPECT_NE(e.find("catalogue.yaml:12:"), std::string::npos) << e;
  EXPECT_NE(e.find("second YAML document"), std::string::npos) << e;
}

// --- a patch that breaks the circuit -------------------------------------

TEST(DiagnoseInputs, PatchWithADanglingPortIsRefusedAtLoad) {
  const std::string e = catalogue_error(R"(effects:
  half_leak:
    parameters:
      C: {initial: 2.0e-10, lower: 0, upper: 5.0e-9, null: 0, unit: m3/(s*Pa)}
    add_components:
      leak_path: {type: iso6358_throttle, C: "${C}", b: 0.3}
    connect:
      - [tank.port, leak_path.a]
)");
  EXPECT_NE(e.find("catalogue.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("effect 'half_leak'"), std::string::npos) << e;
  EXPECT_NE(e.find("dangling"), std::string::npos) << e;
}

TEST(DiagnoseInputs, PatchJoiningTwoSourcesIsRefusedAtLoad) {
  const std::string e = catalogue_error(R"(effects:
  second_supply:
    parameters:
      p: {initial: 5.0e5, lower: 1.0e5, upper: 8.0e5, unit: Pa}
    add_components:
      supply2: {type: pressure_source, p: "${p}", T: 293.15}
    connect:
      - [supply.port, supply2.port]
)");
  EXPECT_NE(e.find("catalogue.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("effect 'second_supply'"), std::string::npos) << e;
}

}  // namespace
}  // namespace pneumo
