// The lab data-file description reads the TU Delft files as they come:
// whitespace without a header, semicolons with '.' as both thousands
// separator and decimal mark, raw volts through a linear scale.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "framework/io/data_file.hpp"

namespace {

using pneumo::DataColumnSpec;
using pneumo::DataFileSpec;
using pneumo::DataSeparator;

const std::string kDir = std::string(PNEUMO_SOURCE_DIR) + "/tests/data/tudelft/";
constexpr double kAmb = 101325.0;

DataFileSpec leak_spec(char thousands) {
  DataFileSpec s;
  s.file = kDir + "Ultimaker_015_excerpt.csv";
  s.separator = DataSeparator::semicolon;
  s.header = false;
  s.thousands = thousands;
  s.columns = {DataColumnSpec{"t", 1, "", "ms"}, DataColumnSpec{"p", 3, "", "bar g"}};
  return s;
}

TEST(DataFile, ThousandsSeparatorEqualToTheDecimalMarkReadsTheLeakDownTime) {
  const auto d = pneumo::read_data_file(leak_spec('.'), kAmb);
  ASSERT_EQ(d.rows(), 36u);
  const auto& t = d.values[0];
  EXPECT_DOUBLE_EQ(t[1], 0.1);     // "100.000" ms
  EXPECT_DOUBLE_EQ(t[10], 1.0);    // "1.000.000" ms (file line 11)
  EXPECT_EQ(d.lines[10], 11);
  EXPECT_DOUBLE_EQ(t[16], 10.458);  // "10.458.000" ms
  // 10 Hz logging: within each of the excerpt's three blocks (rows 0-11,
  // 12-27, 28-35) the samples are 0.1 s apart.
  for (std::size_t i = 1; i < t.size(); ++i)
    if (i != 12 && i != 28) EXPECT_NEAR(t[i] - t[i - 1], 0.1, 0.0011) << "line " << d.lines[i];
  // bar gauge becomes absolute Pa.
  EXPECT_NEAR(d.values[1][0], 7.652e5 + kAmb, 1e-6);
}

TEST(DataFile, TheLeakDownTimeWithoutAThousandsSeparatorIsRefusedAtItsLine) {
  try {
    pneumo::read_data_file(leak_spec(0), kAmb);
    FAIL() << "1.000.000 read as a number without a thousands separator";
  } catch (const pneumo::InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("Ultimaker_015_excerpt.csv:11"), std::string::npos) << m;
    EXPECT_NE(m.find("'1.000.000'"), std::string::npos) << m;
    EXPECT_NE(m.find("thousands separator none"), std::string::npos) << m;
  }
}

DataFileSpec friction_spec() {
  DataFileSpec s;
  s.file = kDir + "O-ring_3bar_head.csv";
  s.separator = DataSeparator::whitespace;
  s.header = false;
  s.columns = {DataColumnSpec{"t", 1, "", "ms"}, DataColumnSpec{"s", 5, "", "mm"},
               DataColumnSpec{"p", 6, "", "bar g"}, DataColumnSpec{"p_raw", 3, "", "bar g", 2.0, 0.0}};
  return s;
}

TEST(DataFile, WhitespaceWithoutHeaderAndAVoltColumnThroughALinearScale) {
  const auto d = pneumo::read_data_file(friction_spec(), kAmb);
  ASSERT_EQ(d.rows(), 400u);
  EXPECT_DOUBLE_EQ(d.values[0][1], 0.010);       // 10 ms
  EXPECT_NEAR(d.values[1][11], 0.232e-3, 1e-12);  // 0.232 mm
  // The transducer's raw volts at 2 bar/V are the file's bar column
  // (both written with three decimals: within 2 mV * 2 bar/V).
  for (std::size_t i = 0; i < d.rows(); ++i) EXPECT_NEAR(d.values[3][i], d.values[2][i], 0.004e5 + 1e-6);
}

TEST(DataFile, SkippedRowsAreNotRead) {
  auto s = friction_spec();
  s.skip_rows = 15;  // the start-up transient
  const auto d = pneumo::read_data_file(s, kAmb);
  ASSERT_EQ(d.rows(), 385u);
  EXPECT_EQ(d.lines.front(), 16);
}

TEST(DataFile, HeaderNamesCommaDecimalsAndThousandsPoints) {
  DataFileSpec s;
  s.file = "euro.csv";
  s.separator = DataSeparator::semicolon;
  s.decimal = ',';
  s.thousands = '.';
  s.columns = {DataColumnSpec{"t", 0, "Zeit", "ms"}, DataColumnSpec{"F", 0, "Kraft", "N"}};
  const auto d = pneumo::parse_data_file(s, "Kraft;Zeit\n12,5;1.234,5\n-3;2.000\n", kAmb);
  ASSERT_EQ(d.rows(), 2u);
  EXPECT_DOUBLE_EQ(d.values[0][0], 1.2345);
  EXPECT_DOUBLE_EQ(d.values[0][1], 2.0);
  EXPECT_DOUBLE_EQ(d.values[1][0], 12.5);
  EXPECT_DOUBLE_EQ(d.values[1][1], -3.0);
  // A group of other than three digits is no thousands grouping.
  EXPECT_THROW(pneumo::parse_data_file(s, "Kraft;Zeit\n1;1.23,5\n", kAmb), pneumo::InputError);
}

TEST(DataFile, AColumnBeyondTheRowOrAMissingHeaderNameIsRefused) {
  auto s = friction_spec();
  s.columns.push_back(DataColumnSpec{"x", 8, "", ""});
  try {
    pneumo::read_data_file(s, kAmb);
    FAIL();
  } catch (const pneumo::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is column 8 but the row has 7 values"), std::string::npos) << e.what();
  }
  DataFileSpec h;
  h.file = "h.csv";
  h.columns = {DataColumnSpec{"t", 0, "time", "s"}};
  try {
    pneumo::parse_data_file(h, "t,p\n1,2\n", kAmb);
    FAIL();
  } catch (const pneumo::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("has no cell 'time' (it has: t, p)"), std::string::npos) << e.what();
  }
}

// The laser's reading jumps now and then by 0.1-0.5 mm for a sample or
// two; the rod, at under 20 mm/s, moves under 0.2 mm in 10 ms and runs
// smoothly. A running median of five removes the jumps and leaves every
// sample whose five neighbours are monotone exactly as measured.
int jumps(const std::vector<double>& x) {
  int n = 0;
  for (std::size_t i = 1; i + 1 < x.size(); ++i)
    if (std::fabs(x[i] - 0.5 * (x[i - 1] + x[i + 1])) > 0.15e-3) ++n;
  return n;
}

bool monotone(const std::vector<double>& x, std::size_t i) {
  bool up = true, down = true;
  for (std::size_t j = i - 2; j < i + 2; ++j) {
    up = up && x[j + 1] >= x[j];
    down = down && x[j + 1] <= x[j];
  }
  return up || down;
}

TEST(DataFile, ARunningMedianRemovesTheLasersJumpsAndKeepsEveryMonotoneStretch) {
  auto s = friction_spec();
  s.file = kDir + "O-ring_3bar_head1000.csv";
  s.skip_rows = 15;
  const auto raw = pneumo::read_data_file(s, kAmb).values[1];
  s.columns[1].median = 5;
  const auto filtered = pneumo::read_data_file(s, kAmb).values[1];
  ASSERT_EQ(raw.size(), filtered.size());
  EXPECT_GE(jumps(raw), 10);
  EXPECT_EQ(jumps(filtered), 0);
  int kept = 0;
  for (std::size_t i = 2; i + 2 < raw.size(); ++i)
    if (monotone(raw, i)) {
      EXPECT_EQ(filtered[i], raw[i]) << "sample " << i;
      ++kept;
    }
  EXPECT_GT(kept, 800);  // of 985: the strokes' ramps
  s.columns[1].median = 4;
  EXPECT_THROW(pneumo::read_data_file(s, kAmb), pneumo::InputError);
}

// The rod at 6 mm/s, logged every 10 ms with a 290 ms gap in the logging
// and each reading off by +-0.03 mm in turn (timing jitter): the running
// line keeps the ramp exact across the gap and cuts the jitter's swing of
// the difference quotient - the replayed velocity - to under a quarter
// (where the whole window fits in the file).
TEST(DataFile, ARunningLineKeepsARampAcrossALoggingGapAndCalmsItsJitter) {
  std::string exact, jittered;
  std::vector<double> t_ms;
  for (int i = 0; i < 40; ++i) t_ms.push_back(10.0 * i + (i >= 20 ? 280.0 : 0.0));
  for (std::size_t i = 0; i < t_ms.size(); ++i) {
    const double x = 6e-3 * t_ms[i];  // mm at 6 mm/s
    exact += std::to_string(t_ms[i]) + "," + std::to_string(x) + "\n";
    jittered += std::to_string(t_ms[i]) + "," + std::to_string(x + (i % 2 ? 0.03 : -0.03)) + "\n";
  }
  DataFileSpec s;
  s.file = "ramp.csv";
  s.header = false;
  s.columns = {DataColumnSpec{"t", 1, "", "ms"}, DataColumnSpec{"s", 2, "", "mm"}};
  s.columns[1].average = 5;
  const auto ramp = pneumo::parse_data_file(s, exact, kAmb);
  for (std::size_t i = 0; i < ramp.rows(); ++i) EXPECT_NEAR(ramp.values[1][i], 6e-3 * ramp.values[0][i], 1e-12);
  const auto d = pneumo::parse_data_file(s, jittered, kAmb);
  for (std::size_t i = 3; i + 2 < d.rows(); ++i) {  // the window shrinks at the file's ends
    const double v = (d.values[1][i] - d.values[1][i - 1]) / (d.values[0][i] - d.values[0][i - 1]);
    EXPECT_LT(std::fabs(v - 6e-3), 0.25 * 0.06e-3 / 0.010) << "sample " << i;  // raw: +-6 mm/s about 6 mm/s
  }
  s.columns[1].average = 2;
  EXPECT_THROW(pneumo::parse_data_file(s, exact, kAmb), pneumo::InputError);
}

}  // namespace
