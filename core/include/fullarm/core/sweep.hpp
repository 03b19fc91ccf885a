#pragma once
/// @file
/// The sweep engine: N samples, each evaluated from its own seeded random stream, so a sweep's
/// results are the same whatever the thread count, the process count and the order the samples
/// run in. A sweep runs on the job pool in one process, or is cut into shards (`--shard i/N`,
/// for job arrays or GNU parallel) whose files a merge puts back together; the MPI spread and
/// gather lives in `fullarm::mpi` so that core users do not depend on MPI (docs/architecture.md).
/// Offline (allocates, locks), not @rt.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "fullarm/core/random.hpp"

namespace fullarm::core {

/// What fixes a sweep's results: a shard or a merge refuses to mix results of two different ones.
struct SweepSpec {
  std::string name;             ///< what is swept (one word, no spaces); also keys the random stream
  std::int64_t samples = 0;     ///< number of samples (>= 1)
  std::uint64_t seed = 0;       ///< the run's seed
  std::uint64_t input_hash = 0; ///< hash of every other input (sweepInputHash of their text)
  int values_per_sample = 1;    ///< doubles each sample produces (>= 1)
};

/// One shard of a sweep: shard `index` of `count` (1-based, as written `index/count`).
struct ShardSpec {
  int index = 1;  ///< 1..count
  int count = 1;  ///< >= 1
};

/// The samples [begin, end) a shard owns: contiguous blocks, begin = samples (index-1) / count.
struct SampleRange {
  std::int64_t begin = 0;
  std::int64_t end = 0;
};

/// The results of a sweep or of one shard of it: one row of spec.values_per_sample doubles per
/// sample, in sample order.
struct SweepResults {
  std::filesystem::path source;      ///< file it was read from (empty when computed)
  SweepSpec spec;
  ShardSpec shard;                   ///< which shard ({1, 1} for a whole or merged sweep)
  std::vector<std::int64_t> sample;  ///< the sample of each row, increasing
  std::vector<double> values;        ///< row-major, sample.size() x spec.values_per_sample

  /// The values of row `row`.
  [[nodiscard]] std::span<const double> row(std::size_t row) const {
    const auto w = static_cast<std::size_t>(spec.values_per_sample);
    return {values.data() + row * w, w};
  }
};

/// Evaluates one sample: `rng` is the sample's own stream (seed, nameSlot(spec.name), sample);
/// writes spec.values_per_sample doubles to `out`. Called concurrently for different samples.
using SweepFunction = std::function<void(std::int64_t sample, RandomStream& rng, std::span<double> out)>;

/// Parses `i/N` (1 <= i <= N, both decimal integers).
/// @throws ConfigError (key `--shard`) naming the text and what was expected.
[[nodiscard]] ShardSpec parseShardSpec(std::string_view text);

/// The samples shard `shard` owns among `samples`.
/// @throws ConfigError when the shard is out of range or samples < 1.
[[nodiscard]] SampleRange shardRange(std::int64_t samples, const ShardSpec& shard);

/// 64-bit FNV-1a of `text`: the input hash of a sweep (hash the text of every input that changes
/// its results: options, files).
[[nodiscard]] std::uint64_t sweepInputHash(std::string_view text) noexcept;

/// Checks a spec (name one non-empty word, samples >= 1, values_per_sample >= 1).
/// @throws ConfigError naming the field.
void validateSweepSpec(const SweepSpec& spec);

/// Runs the samples of `shard` with `threads` workers (>= 1) of a core::JobPool. Each sample is
/// evaluated once from its own stream, so the results do not depend on `threads`. When samples
/// throw, rethrows the exception of the lowest-numbered one. `progress` (optional) is called
/// after each sample with the number done so far (from the worker thread, serialised).
[[nodiscard]] SweepResults runSweep(const SweepSpec& spec, const ShardSpec& shard, const SweepFunction& evaluate,
                                    int threads, const std::function<void(std::int64_t done)>& progress = {});

/// Writes a shard's results: a text header (format version, name, samples, seed, input hash,
/// values per sample, shard) and one line per sample with its values as exact hexadecimal floats.
/// @throws std::runtime_error when the file cannot be written.
void writeSweepResults(const SweepResults& results, const std::filesystem::path& file);

/// Reads what writeSweepResults wrote.
/// @throws ConfigError naming the file, line and what is wrong.
[[nodiscard]] SweepResults readSweepResults(const std::filesystem::path& file);

/// Puts shards back into the whole sweep. Refuses (ConfigError naming the shard and field) shards
/// of different sweeps (name, samples, seed, input hash, values per sample or shard count differ),
/// a shard given twice, a missing shard, a sample outside its shard's range, and any sample not
/// present exactly once.
[[nodiscard]] SweepResults mergeSweepResults(const std::vector<SweepResults>& shards);

}  // namespace fullarm::core
