#include "fullarm/core/sweep.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>

#include "fullarm/core/config_error.hpp"
#include "scratch_dir.hpp"

namespace fullarm::core {
namespace {

constexpr int kValues = 3;

SweepSpec testSpec(std::int64_t samples = 203) {
  SweepSpec spec;
  spec.name = "sweep_test";
  spec.samples = samples;
  spec.seed = 20261127;
  spec.input_hash = sweepInputHash("inputs of the test sweep");
  spec.values_per_sample = kValues;
  return spec;
}

// A sample's values: a few draws of its stream, a value that depends on the draws nonlinearly,
// and the sample number; NaN and infinities included so the files carry them exactly.
void evaluate(std::int64_t sample, RandomStream& rng, std::span<double> out) {
  const double a = rng.uniform01();
  const double b = rng.uniform(-1.0, 1.0);
  out[0] = a;
  out[1] = std::sin(1e3 * a) * b;
  out[2] = sample % 50 == 7 ? std::numeric_limits<double>::quiet_NaN()
                            : (sample % 50 == 9 ? -std::numeric_limits<double>::infinity() : static_cast<double>(sample));
}

// The same values computed one by one in a plain loop: the reference a sweep must match.
std::vector<double> sequentialReference(const SweepSpec& spec) {
  std::vector<double> v(static_cast<std::size_t>(spec.samples * kValues));
  for (std::int64_t s = 0; s < spec.samples; ++s) {
    RandomStream rng(spec.seed, static_cast<std::uint64_t>(nameSlot(spec.name)), static_cast<std::uint64_t>(s));
    evaluate(s, rng, std::span<double>(v.data() + s * kValues, kValues));
  }
  return v;
}

// Bitwise equality, NaN equal to NaN.
void expectSameValues(const std::vector<double>& a, const std::vector<double>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i]) || std::isnan(b[i])) {
      EXPECT_TRUE(std::isnan(a[i]) && std::isnan(b[i])) << "value " << i;
    } else {
      EXPECT_EQ(a[i], b[i]) << "value " << i;
    }
  }
}

TEST(Sweep, OneAndTwoThreadsGiveTheSequentialResults) {
  const SweepSpec spec = testSpec();
  const SweepResults one = runSweep(spec, {1, 1}, evaluate, 1);
  const SweepResults two = runSweep(spec, {1, 1}, evaluate, 2);
  const std::vector<double> ref = sequentialReference(spec);
  expectSameValues(one.values, ref);
  expectSameValues(two.values, ref);
  ASSERT_EQ(one.sample.size(), 203u);
  for (std::size_t i = 0; i < one.sample.size(); ++i) EXPECT_EQ(one.sample[i], static_cast<std::int64_t>(i));
}

TEST(Sweep, ProgressCountsEverySampleOnce) {
  std::int64_t last = 0;
  int calls = 0;
  (void)runSweep(testSpec(40), {1, 1}, evaluate, 2, [&](std::int64_t done) {
    EXPECT_EQ(done, last + 1);
    last = done;
    ++calls;
  });
  EXPECT_EQ(calls, 40);
}

TEST(Sweep, TheLowestFailingSampleIsReported) {
  const auto failing = [](std::int64_t sample, RandomStream&, std::span<double>) {
    if (sample == 33 || sample == 150) throw std::runtime_error("sample " + std::to_string(sample));
  };
  for (const int threads : {1, 2}) {
    try {
      (void)runSweep(testSpec(), {1, 1}, failing, threads);
      ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "sample 33");
    }
  }
}

TEST(Sweep, ShardsCoverTheSamplesOnceInContiguousBlocks) {
  for (const std::int64_t n : {1, 2, 7, 203}) {
    for (const int count : {1, 2, 3, 8}) {
      std::int64_t next = 0;
      for (int i = 1; i <= count; ++i) {
        const SampleRange r = shardRange(n, {i, count});
        EXPECT_EQ(r.begin, next);
        EXPECT_GE(r.end, r.begin);
        next = r.end;
      }
      EXPECT_EQ(next, n);
    }
  }
}

TEST(Sweep, TwoShardsWrittenReadAndMergedGiveTheWholeSweep) {
  const auto dir = fullarm::test::scratchDir("sweep_test_shards");
  const SweepSpec spec = testSpec();
  writeSweepResults(runSweep(spec, {2, 2}, evaluate, 2), dir / "2.sweep");
  writeSweepResults(runSweep(spec, {1, 2}, evaluate, 1), dir / "1.sweep");
  const SweepResults second = readSweepResults(dir / "2.sweep");
  const SweepResults first = readSweepResults(dir / "1.sweep");
  EXPECT_EQ(first.spec.input_hash, spec.input_hash);
  EXPECT_EQ(first.spec.seed, spec.seed);
  const SweepResults merged = mergeSweepResults({second, first});  // any order
  EXPECT_EQ(merged.shard.count, 1);
  expectSameValues(merged.values, sequentialReference(spec));
  ASSERT_EQ(merged.sample.size(), 203u);
  EXPECT_EQ(merged.sample.back(), 202);
}

void expectShardError(std::string_view text, std::string_view fragment) {
  try {
    (void)parseShardSpec(text);
    ADD_FAILURE() << "'" << text << "' was accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.keyPath(), "--shard");
    EXPECT_NE(e.message().find(fragment), std::string::npos) << e.what();
    EXPECT_NE(e.message().find(std::string(text)), std::string::npos) << "names the text: " << e.what();
  }
}

TEST(Sweep, BadShardSpecsAreRefusedWithClearErrors) {
  expectShardError("0/2", "shards count from 1");
  expectShardError("3/2", "between 1 and N = 2");
  expectShardError("a/b", "expected i/N");
  expectShardError("NaN", "expected i/N");
  expectShardError("1/NaN", "expected i/N");
  expectShardError("1/0", "shard count N");
  expectShardError("-1/2", "shards count from 1");
  expectShardError("1/2/3", "expected i/N");
  expectShardError(" 1/2", "expected i/N");
  expectShardError("", "expected i/N");
  const ShardSpec ok = parseShardSpec("2/3");
  EXPECT_EQ(ok.index, 2);
  EXPECT_EQ(ok.count, 3);
}

void expectMergeError(const std::vector<SweepResults>& shards, std::string_view fragment) {
  try {
    (void)mergeSweepResults(shards);
    ADD_FAILURE() << "the merge accepted them";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(Sweep, MergeRefusesMissingDuplicatedAndMismatchedShards) {
  const SweepSpec spec = testSpec();
  const SweepResults a = runSweep(spec, {1, 3}, evaluate, 1);
  const SweepResults b = runSweep(spec, {2, 3}, evaluate, 1);
  const SweepResults c = runSweep(spec, {3, 3}, evaluate, 1);
  EXPECT_NO_THROW((void)mergeSweepResults({a, b, c}));
  expectMergeError({a, c}, "shard 2/3 is missing");
  expectMergeError({a, b, b, c}, "shard 2/3 is given twice");
  expectMergeError({}, "no shard");

  SweepSpec other_seed = spec;
  other_seed.seed += 1;
  expectMergeError({a, runSweep(other_seed, {2, 3}, evaluate, 1), c}, "seed");
  SweepSpec other_inputs = spec;
  other_inputs.input_hash = sweepInputHash("other inputs");
  expectMergeError({a, b, runSweep(other_inputs, {3, 3}, evaluate, 1)}, "input_hash");
  SweepSpec other_samples = spec;
  other_samples.samples = 204;
  expectMergeError({a, b, runSweep(other_samples, {3, 3}, evaluate, 1)}, "samples");
  expectMergeError({a, runSweep(spec, {2, 2}, evaluate, 1)}, "shard count");

  SweepResults lost_row = b;
  lost_row.sample.pop_back();
  lost_row.values.resize(lost_row.values.size() - kValues);
  expectMergeError({a, lost_row, c}, "holds");
  SweepResults repeated = b;
  repeated.sample[1] = repeated.sample[0];
  expectMergeError({a, repeated, c}, "expected sample");
}

TEST(Sweep, ReadingRefusesDamagedFiles) {
  const auto dir = fullarm::test::scratchDir("sweep_test_damaged");
  writeSweepResults(runSweep(testSpec(10), {1, 1}, evaluate, 1), dir / "whole.sweep");
  std::ifstream in(dir / "whole.sweep");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto write = [&](const std::string& name, const std::string& content) {
    std::ofstream(dir / name) << content;
    return dir / name;
  };
  const auto expectReadError = [&](const std::filesystem::path& file, std::string_view key) {
    try {
      (void)readSweepResults(file);
      ADD_FAILURE() << file << " was accepted";
    } catch (const ConfigError& e) {
      EXPECT_EQ(e.file(), file);
      EXPECT_EQ(e.keyPath(), key) << e.what();
    }
  };
  expectReadError(write("truncated.sweep", text.substr(0, text.rfind('\n', text.size() - 2) + 1)), "rows");
  expectReadError(write("version.sweep", "fullarm-sweep 9\n"), "fullarm-sweep");
  std::string bad_shard = text;
  bad_shard.replace(bad_shard.find("shard 1/1"), 9, "shard 0/1");
  expectReadError(write("shard.sweep", bad_shard), "shard");
}

}  // namespace
}  // namespace fullarm::core
