// Experiment logs as LCM logs: a table written and read back is the same table to the bit; the
// reader refuses, naming the file and the byte offset, every way the log can be wrong (no
// description, a sample before it, a second one, a lost or repeated sample, a held count that
// differs, a non-finite value, time that does not increase, a payload that does not decode),
// drops a truncated last event with a warning, skips other channels; a fuzzed log is read or
// refused with a RunLogError, never anything else.

#include "fullarm/identification/experiment_lcm.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <vector>

#include "fullarm/hil/run_log.hpp"
#include "fullarm/identification/experiment.hpp"
#include "fullarm_lcm/heartbeat_t.hpp"
#include "fullarm_lcm/ident_experiment_t.hpp"
#include "fullarm_lcm/ident_sample_t.hpp"

namespace fullarm::identification {
namespace {

std::filesystem::path tempFile(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "fullarm_experiment_lcm_test";
  std::filesystem::create_directories(dir);
  return dir / name;
}

SignalTable table(std::size_t rows) {
  SignalTable t;
  t.names = kExperimentColumns;
  t.names.push_back("held_R_SFE_rad");
  t.names.push_back("held_R_WR_rad");
  t.columns.assign(t.names.size(), {});
  for (std::size_t k = 0; k < rows; ++k) {
    const double x = static_cast<double>(k);
    t.columns[0].push_back(1.001 + 1e-3 * x);  // the device time of the first excitation sample
    t.columns[1].push_back(0.5 * std::sin(0.37 * x));
    t.columns[2].push_back(0.1 / 3.0 + 0.5 * std::sin(0.37 * x));
    t.columns[3].push_back(1.2 + 1e-4 * std::cos(0.11 * x));
    t.columns[4].push_back(10.0 + std::sin(0.05 * x) / 7.0);
    t.columns[5].push_back(-0.3 + 1e-6 * x);
    t.columns[6].push_back(0.7 - 1e-6 * x);
  }
  return t;
}

ExperimentLogInfo info() {
  ExperimentLogInfo i;
  i.command_line = "fullarm identify --io lcm --log-format lcm";
  i.source = "lcm";
  i.joint = "R_EB";
  i.sample_period_s = 1e-3;
  return i;
}

/// A hand-made log: each event as given, for the ways a log can be wrong.
class LogBuilder {
 public:
  explicit LogBuilder(const std::filesystem::path& file) : log_(file.string(), "w") {}
  template <class Message>
  void add(const char* channel, const Message& m) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    addRaw(channel, bytes);
  }
  void addRaw(const char* channel, std::vector<std::uint8_t> bytes) {
    lcm::LogEvent e{};
    e.timestamp = 0;
    e.channel = channel;
    e.datalen = static_cast<std::int32_t>(bytes.size());
    e.data = bytes.data();
    ASSERT_EQ(log_.writeEvent(&e), 0);
  }

 private:
  lcm::LogFile log_;
};

fullarm_lcm::ident_experiment_t header(int held) {
  fullarm_lcm::ident_experiment_t h{};
  h.utime = 0;
  h.joint = "R_EB";
  h.source = "sim";
  h.sample_period_s = 1e-3;
  h.num_held = static_cast<std::int8_t>(held);
  for (int k = 0; k < held; ++k) {
    std::string name = "J";
    name += std::to_string(k);
    h.held_joints.push_back(name);
  }
  return h;
}

fullarm_lcm::ident_sample_t sample(std::int64_t seq, int held) {
  fullarm_lcm::ident_sample_t s{};
  s.utime = seq * 1000;
  s.seq = seq;
  s.t_s = 1e-3 * static_cast<double>(seq);
  s.excitation_v = 0.1;
  s.command_v = 0.2;
  s.q_rad = 1.0;
  s.tau_measured_nm = 5.0;
  s.num_held = static_cast<std::int8_t>(held);
  s.held_q_rad.assign(static_cast<std::size_t>(held), 0.5);
  return s;
}

fullarm_lcm::ident_sample_t sampleWithPressures(std::int64_t seq, double p_a_pa, double p_b_pa) {
  fullarm_lcm::ident_sample_t s = sample(seq, 0);
  s.num_pressures = 2;
  s.pressure_pa = {p_a_pa, p_b_pa};
  return s;
}

void expectRefused(const std::filesystem::path& file, const std::string& says, bool names_offset = true) {
  try {
    (void)readExperimentLcmLog(file);
    ADD_FAILURE() << "accepted; expected: " << says;
  } catch (const hil::RunLogError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file.string()), std::string::npos) << what;
    EXPECT_NE(what.find(says), std::string::npos) << what;
    if (names_offset) {
      EXPECT_NE(what.find("byte offset"), std::string::npos) << what;
    }
  }
}

TEST(ExperimentLcmLogTest, ATableWrittenAndReadBackIsTheSameToTheBit) {
  const auto file = tempFile("round_trip.lcm");
  const SignalTable written = table(500);
  writeExperimentLcmLog(file, written, info());
  EXPECT_TRUE(isLcmLog(file));
  const ExperimentLcmLog read = readExperimentLcmLog(file);
  EXPECT_EQ(read.table.names, written.names);
  ASSERT_EQ(read.table.columns.size(), written.columns.size());
  for (std::size_t c = 0; c < written.columns.size(); ++c) EXPECT_EQ(read.table.columns[c], written.columns[c]) << c;
  EXPECT_EQ(read.info.joint, "R_EB");
  EXPECT_EQ(read.info.source, "lcm");
  EXPECT_EQ(read.info.command_line, info().command_line);
  EXPECT_EQ(read.info.sample_period_s, 1e-3);
  EXPECT_FALSE(read.info.fullarm_version.empty());
  EXPECT_TRUE(read.warning.empty());
  EXPECT_EQ(read.skipped, 0);
  // The held joints' means are those of the CSV log's columns.
  const std::vector<HeldAngle> held = heldAngles(read.table);
  ASSERT_EQ(held.size(), 2u);
  EXPECT_EQ(held[0].joint, "R_SFE");
  EXPECT_EQ(held[1].joint, "R_WR");

  // A CSV log is not an LCM log, and read back it gives the LCM log's table to the bit.
  const auto csv = tempFile("log.csv");
  writeSignalCsv(csv, written);
  EXPECT_FALSE(isLcmLog(csv));
  const SignalTable from_csv = readSignalCsv(csv, kExperimentColumns);
  EXPECT_EQ(from_csv.names, read.table.names);
  EXPECT_EQ(from_csv.columns, read.table.columns);
  // And the writer refuses tables that are not experiment logs.
  SignalTable other = written;
  other.names[5] = "pressure_pa";
  EXPECT_THROW(writeExperimentLcmLog(tempFile("bad.lcm"), other, info()), std::invalid_argument);
  SignalTable missing = written;
  missing.names[2] = "command_mv";
  EXPECT_THROW(writeExperimentLcmLog(tempFile("bad.lcm"), missing, info()), std::invalid_argument);
  // Nor does it write what its reader would refuse: no rows, a NaN, time that does not increase,
  // a period that is not positive.
  EXPECT_THROW(writeExperimentLcmLog(tempFile("bad.lcm"), table(0), info()), std::invalid_argument);
  SignalTable nan = written;
  nan.columns[6][17] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(writeExperimentLcmLog(tempFile("bad.lcm"), nan, info()), std::invalid_argument);
  SignalTable back = written;
  back.columns[0][9] = back.columns[0][8];
  EXPECT_THROW(writeExperimentLcmLog(tempFile("bad.lcm"), back, info()), std::invalid_argument);
  ExperimentLogInfo no_period = info();
  no_period.sample_period_s = 0.0;
  EXPECT_THROW(writeExperimentLcmLog(tempFile("bad.lcm"), written, no_period), std::invalid_argument);
  // A file that cannot be created, and one that runs out of room (/dev/full takes the open and
  // fails every write), are errors naming the file.
  for (const std::filesystem::path& unwritable : {file / "below_a_file.lcm", std::filesystem::path("/dev/full")}) {
    if (unwritable == "/dev/full" && !std::filesystem::is_character_file(unwritable)) continue;
    try {
      writeExperimentLcmLog(unwritable, written, info());
      ADD_FAILURE() << unwritable << " was written";
    } catch (const fullarm::hil::RunLogError& e) {
      EXPECT_NE(std::string(e.what()).find(unwritable.string()), std::string::npos) << e.what();
    }
  }
}

// The driven joint's chamber pressures, where logged, travel with every sample and come back as
// the same columns in the same place (after the five, before the held joints').
TEST(ExperimentLcmLogTest, ChamberPressuresRoundTripToTheBit) {
  SignalTable written = table(300);
  const std::vector<std::string> held_names(written.names.begin() + 5, written.names.end());
  std::vector<std::vector<double>> held_columns(written.columns.begin() + 5, written.columns.end());
  written.names.resize(5);
  written.columns.resize(5);
  written.names.insert(written.names.end(), kPressureColumns.begin(), kPressureColumns.end());
  std::vector<double> pa, pb;
  for (std::size_t k = 0; k < 300; ++k) {
    pa.push_back(1.0e7 + 1.0e5 * std::sin(0.3 * static_cast<double>(k)) / 3.0);
    pb.push_back(0.9e7 - 1.0e5 * std::cos(0.2 * static_cast<double>(k)) / 7.0);
  }
  written.columns.push_back(pa);
  written.columns.push_back(pb);
  written.names.insert(written.names.end(), held_names.begin(), held_names.end());
  written.columns.insert(written.columns.end(), held_columns.begin(), held_columns.end());
  const auto file = tempFile("pressures.lcm");
  writeExperimentLcmLog(file, written, info());
  const ExperimentLcmLog read = readExperimentLcmLog(file);
  EXPECT_EQ(read.table.names, written.names);
  EXPECT_EQ(read.table.columns, written.columns);
  EXPECT_EQ(heldAngles(read.table).size(), 2u);
  // One chamber's pressure without the other's is refused.
  SignalTable one = written;
  one.names.erase(one.names.begin() + 6);
  one.columns.erase(one.columns.begin() + 6);
  EXPECT_THROW(writeExperimentLcmLog(tempFile("one.lcm"), one, info()), std::invalid_argument);
}

// A log written before the chamber pressures were logged (tests/identification/data: the elbow's
// 0.5 s PRBS experiment as `fullarm identify --log-format lcm` 0.1.0 wrote it, in the earlier
// layouts of both types) reads as a log without pressures: the five columns, every sample, its
// description.
TEST(ExperimentLcmLogTest, ALogInTheEarlierLayoutReadsWithoutPressures) {
  const char* root = std::getenv("FULLARM_SOURCE_DIR");
  const std::filesystem::path file =
      std::filesystem::path(root != nullptr ? root : ".") / "tests/identification/data/experiment_before_pressures.lcm";
  ASSERT_TRUE(std::filesystem::exists(file)) << file;
  const ExperimentLcmLog read = readExperimentLcmLog(file);
  EXPECT_EQ(read.table.names, kExperimentColumns);
  ASSERT_EQ(read.table.rows(), 500u);
  EXPECT_EQ(read.info.joint, "R_EB");
  EXPECT_EQ(read.info.source, "sim");
  EXPECT_EQ(read.info.fullarm_version, "0.1.0");
  EXPECT_EQ(read.info.sample_period_s, 1e-3);
  EXPECT_NE(read.info.command_line.find("--log-format lcm"), std::string::npos) << read.info.command_line;
  EXPECT_TRUE(read.warning.empty());
  const std::vector<double>& t = read.table.column("time_s");
  for (std::size_t k = 1; k < t.size(); ++k) EXPECT_NEAR(t[k] - t[k - 1], 1e-3, 1e-9) << k;
  // The PRBS of +-0.5 V, and the elbow near its default angle.
  for (double r : read.table.column("excitation_v")) EXPECT_EQ(std::abs(r), 0.5);
  for (double q : read.table.column("q_rad")) EXPECT_NEAR(q, 1.54, 0.05);
  // Written again it is a log in the current layout with the same rows.
  const auto again = tempFile("earlier_rewritten.lcm");
  writeExperimentLcmLog(again, read.table, read.info);
  EXPECT_EQ(readExperimentLcmLog(again).table.columns, read.table.columns);
}

TEST(ExperimentLcmLogTest, OtherChannelsAreSkippedAndATruncatedLastEventIsDroppedWithAWarning) {
  const auto file = tempFile("mixed.lcm");
  {
    LogBuilder b(file);
    fullarm_lcm::heartbeat_t beat{};
    b.add("FULLARM_HEARTBEAT", beat);
    b.add(channel::kIdentExperiment, header(1));
    for (int k = 0; k < 5; ++k) {
      b.add(channel::kIdentSample, sample(k, 1));
      b.add("FULLARM_HEARTBEAT", beat);
    }
  }
  const ExperimentLcmLog read = readExperimentLcmLog(file);
  EXPECT_EQ(read.table.rows(), 5u);
  EXPECT_EQ(read.skipped, 6);
  EXPECT_EQ(read.table.names.back(), "held_J0_rad");

  // Cut into the last sample: four rows and a warning naming the file.
  const auto cut = tempFile("cut.lcm");
  {
    LogBuilder b(cut);
    b.add(channel::kIdentExperiment, header(1));
    for (int k = 0; k < 5; ++k) b.add(channel::kIdentSample, sample(k, 1));
  }
  std::filesystem::resize_file(cut, std::filesystem::file_size(cut) - 7);
  const ExperimentLcmLog truncated = readExperimentLcmLog(cut);
  EXPECT_EQ(truncated.table.rows(), 4u);
  EXPECT_NE(truncated.warning.find(cut.string()), std::string::npos) << truncated.warning;
  EXPECT_NE(truncated.warning.find("truncated"), std::string::npos) << truncated.warning;
}

TEST(ExperimentLcmLogTest, EveryWayALogCanBeWrongIsRefusedNamingTheFileAndTheOffset) {
  const auto write = [](const std::string& name, const std::function<void(LogBuilder&)>& events) {
    const auto file = tempFile(name);
    {
      LogBuilder b(file);
      events(b);
    }
    return file;
  };
  {
    const auto empty = tempFile("empty.lcm");
    std::ofstream(empty).close();
    expectRefused(empty, "not an identification experiment log", false);
  }
  expectRefused(write("no_header.lcm", [](LogBuilder& b) { b.add(channel::kIdentSample, sample(0, 0)); }),
                "a sample before the experiment description");
  {
    fullarm_lcm::ident_experiment_t three = header(0);
    three.num_pressures = 3;
    expectRefused(write("three_pressures.lcm",
                        [&](LogBuilder& b) {
                          b.add(channel::kIdentExperiment, three);
                          b.add(channel::kIdentSample, sample(0, 0));
                        }),
                  "num_pressures 3: expected 0 or 2");
    // A description with both chamber pressures, a first sample that carries them, then `second`.
    const auto withPressures = [&](const std::string& name, const fullarm_lcm::ident_sample_t& second) {
      fullarm_lcm::ident_experiment_t two = header(0);
      two.num_pressures = 2;
      return write(name, [&](LogBuilder& b) {
        b.add(channel::kIdentExperiment, two);
        b.add(channel::kIdentSample, sampleWithPressures(0, 1.0e7, 0.9e7));
        b.add(channel::kIdentSample, second);
      });
    };
    expectRefused(withPressures("pressure_count.lcm", sample(1, 0)), "carries 0 chamber pressures, the description 2");
    expectRefused(
        withPressures("pressure_inf.lcm", sampleWithPressures(1, 1.0e7, std::numeric_limits<double>::infinity())),
        "pressure_b_pa is inf");
  }
  expectRefused(write("no_samples.lcm", [](LogBuilder& b) { b.add(channel::kIdentExperiment, header(0)); }),
                "has no samples", false);
  expectRefused(write("two_headers.lcm",
                      [](LogBuilder& b) {
                        b.add(channel::kIdentExperiment, header(0));
                        b.add(channel::kIdentSample, sample(0, 0));
                        b.add(channel::kIdentExperiment, header(0));
                      }),
                "a second experiment description");
  expectRefused(write("gap.lcm",
                      [](LogBuilder& b) {
                        b.add(channel::kIdentExperiment, header(0));
                        b.add(channel::kIdentSample, sample(0, 0));
                        b.add(channel::kIdentSample, sample(2, 0));
                      }),
                "samples are missing");
  expectRefused(write("repeat.lcm",
                      [](LogBuilder& b) {
                        b.add(channel::kIdentExperiment, header(0));
                        b.add(channel::kIdentSample, sample(0, 0));
                        b.add(channel::kIdentSample, sample(0, 0));
                      }),
                "repeated or out of order");
  expectRefused(write("held_count.lcm",
                      [](LogBuilder& b) {
                        b.add(channel::kIdentExperiment, header(2));
                        b.add(channel::kIdentSample, sample(0, 1));
                      }),
                "carries 1 held angles, the description 2");
  expectRefused(write("nan.lcm",
                      [](LogBuilder& b) {
                        b.add(channel::kIdentExperiment, header(0));
                        auto s = sample(0, 0);
                        s.tau_measured_nm = std::numeric_limits<double>::quiet_NaN();
                        b.add(channel::kIdentSample, s);
                      }),
                "tau_measured_nm is nan");
  expectRefused(write("held_inf.lcm",
                      [](LogBuilder& b) {
                        b.add(channel::kIdentExperiment, header(1));
                        auto s = sample(0, 1);
                        s.held_q_rad[0] = std::numeric_limits<double>::infinity();
                        b.add(channel::kIdentSample, s);
                      }),
                "held joint J0's angle is inf");
  expectRefused(write("time.lcm",
                      [](LogBuilder& b) {
                        b.add(channel::kIdentExperiment, header(0));
                        b.add(channel::kIdentSample, sample(0, 0));
                        auto s = sample(1, 0);
                        s.t_s = 0.0;
                        b.add(channel::kIdentSample, s);
                      }),
                "expected time to increase");
  expectRefused(write("period.lcm",
                      [](LogBuilder& b) {
                        auto h = header(0);
                        h.sample_period_s = -1e-3;
                        b.add(channel::kIdentExperiment, h);
                      }),
                "expected a positive period");
  expectRefused(write("duplicate_held.lcm",
                      [](LogBuilder& b) {
                        auto h = header(2);
                        h.held_joints[1] = h.held_joints[0];
                        b.add(channel::kIdentExperiment, h);
                      }),
                "named twice");
  expectRefused(write("short_payload.lcm",
                      [](LogBuilder& b) {
                        b.add(channel::kIdentExperiment, header(0));
                        std::vector<std::uint8_t> bytes(static_cast<std::size_t>(sample(0, 0).getEncodedSize()));
                        sample(0, 0).encode(bytes.data(), 0, static_cast<int>(bytes.size()));
                        bytes.resize(bytes.size() - 3);
                        b.addRaw(channel::kIdentSample, bytes);
                      }),
                "does not decode as ident_sample_t");
  expectRefused(write("too_many_held.lcm",
                      [](LogBuilder& b) {
                        b.add(channel::kIdentExperiment, header(65));
                        b.add(channel::kIdentSample, sample(0, 65));
                      }),
                "num_held 65: expected 0 to 64");
  expectRefused(write("no_joint.lcm",
                      [](LogBuilder& b) {
                        auto h = header(0);
                        h.joint.clear();
                        b.add(channel::kIdentExperiment, h);
                      }),
                "joint is empty");
  expectRefused(write("comma.lcm",
                      [](LogBuilder& b) {
                        auto h = header(1);
                        h.held_joints[0] = "R,SFE";
                        b.add(channel::kIdentExperiment, h);
                      }),
                "held joint 'R,SFE': expected a joint name");
  expectRefused(write("period_mismatch.lcm",
                      [](LogBuilder& b) {
                        auto h = header(0);
                        h.sample_period_s = 2e-3;
                        b.add(channel::kIdentExperiment, h);
                        for (int k = 0; k < 3; ++k) b.add(channel::kIdentSample, sample(k, 0));
                      }),
                "the description says every 0.002", false);
  // A CSV file handed to the LCM reader.
  const auto csv = tempFile("not_lcm.csv");
  writeSignalCsv(csv, table(10));
  EXPECT_THROW((void)readExperimentLcmLog(csv), hil::RunLogError);
}

TEST(ExperimentLcmLogTest, FuzzedLogsAreReadOrRefusedWithARunLogError) {
  const auto good = tempFile("fuzz_source.lcm");
  writeExperimentLcmLog(good, table(40), info());
  std::vector<char> bytes(std::filesystem::file_size(good));
  std::ifstream(good, std::ios::binary).read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  std::mt19937 rng(11);
  int read = 0, refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<char> mutated = bytes;
    std::uniform_int_distribution<std::size_t> at(0, mutated.size() - 1);
    const int flips = 1 + trial % 4;
    for (int f = 0; f < flips; ++f) mutated[at(rng)] = static_cast<char>(rng());
    if (trial % 5 == 0) mutated.resize(at(rng));
    const auto file = tempFile("fuzz.lcm");
    std::ofstream(file, std::ios::binary | std::ios::trunc)
        .write(mutated.data(), static_cast<std::streamsize>(mutated.size()));
    try {
      const ExperimentLcmLog log = readExperimentLcmLog(file);
      // Whatever was read is a well-formed table: every column as long as the time, all finite.
      for (const auto& column : log.table.columns) {
        ASSERT_EQ(column.size(), log.table.rows());
        for (double v : column) ASSERT_TRUE(std::isfinite(v));
      }
      ++read;
    } catch (const hil::RunLogError& e) {
      EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
      ++refused;
    }
  }
  std::printf("fuzzed logs: %d read, %d refused\n", read, refused);
  EXPECT_GT(refused, 0);
}

}  // namespace
}  // namespace fullarm::identification
