#include "fullarm/core/sweep.hpp"

#include <algorithm>
#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "fullarm/core/config_error.hpp"
#include "fullarm/core/job_pool.hpp"

namespace fullarm::core {
namespace {

constexpr std::string_view kMagic = "fullarm-sweep";
constexpr int kFormatVersion = 1;
constexpr std::int64_t kBlock = 16;  // samples per pool job

bool parseInt(std::string_view text, std::int64_t& value) {
  if (text.empty()) return false;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  return ec == std::errc() && ptr == end;
}

bool parseU64(std::string_view text, std::uint64_t& value, int base = 10) {
  if (text.empty()) return false;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value, base);
  return ec == std::errc() && ptr == end;
}

std::string shardName(const ShardSpec& s) { return std::to_string(s.index) + "/" + std::to_string(s.count); }

std::string describe(const SweepResults& r) {
  return "shard " + shardName(r.shard) + (r.source.empty() ? std::string() : " (" + r.source.string() + ")");
}

}  // namespace

ShardSpec parseShardSpec(std::string_view text) {
  const auto fail = [&](const std::string& why) {
    throw ConfigError({}, "--shard", "'" + std::string(text) + "': " + why);
  };
  const auto slash = text.find('/');
  if (slash == std::string_view::npos) fail("expected i/N with integers 1 <= i <= N (for example 1/4)");
  std::int64_t i = 0;
  std::int64_t n = 0;
  if (!parseInt(text.substr(0, slash), i) || !parseInt(text.substr(slash + 1), n)) {
    fail("expected i/N with integers 1 <= i <= N (for example 1/4)");
  }
  if (n < 1 || n > 1'000'000) fail("the shard count N must be between 1 and 1000000");
  if (i < 1 || i > n) fail("the shard index i must be between 1 and N = " + std::to_string(n) + " (shards count from 1)");
  return {static_cast<int>(i), static_cast<int>(n)};
}

SampleRange shardRange(std::int64_t samples, const ShardSpec& shard) {
  if (samples < 1) throw ConfigError({}, "samples", std::to_string(samples) + ": expected at least 1 sample");
  if (shard.count < 1 || shard.index < 1 || shard.index > shard.count) {
    throw ConfigError({}, "--shard", shardName(shard) + ": expected i/N with 1 <= i <= N");
  }
  // samples * index fits: samples is a count of evaluations, far below 2^63 / 10^6.
  return {samples * (shard.index - 1) / shard.count, samples * shard.index / shard.count};
}

std::uint64_t sweepInputHash(std::string_view text) noexcept {
  std::uint64_t h = 14695981039346656037ULL;  // FNV-1a 64 (Fowler, Noll and Vo)
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ULL;
  }
  return h;
}

void validateSweepSpec(const SweepSpec& spec) {
  if (spec.name.empty() || spec.name.find_first_of(" \t\r\n") != std::string::npos) {
    throw ConfigError({}, "sweep.name", "'" + spec.name + "': expected one non-empty word");
  }
  if (spec.samples < 1) {
    throw ConfigError({}, "sweep.samples", std::to_string(spec.samples) + ": expected at least 1 sample");
  }
  if (spec.values_per_sample < 1) {
    throw ConfigError({}, "sweep.values_per_sample", std::to_string(spec.values_per_sample) + ": expected >= 1");
  }
}

SweepResults runSweep(const SweepSpec& spec, const ShardSpec& shard, const SweepFunction& evaluate, int threads,
                      const std::function<void(std::int64_t done)>& progress) {
  validateSweepSpec(spec);
  const SampleRange range = shardRange(spec.samples, shard);
  const std::int64_t n = range.end - range.begin;
  const auto w = static_cast<std::size_t>(spec.values_per_sample);
  SweepResults r;
  r.spec = spec;
  r.shard = shard;
  r.sample.resize(static_cast<std::size_t>(n));
  r.values.assign(static_cast<std::size_t>(n) * w, 0.0);
  for (std::int64_t k = 0; k < n; ++k) r.sample[static_cast<std::size_t>(k)] = range.begin + k;
  const auto stream = static_cast<std::uint64_t>(nameSlot(spec.name));
  std::mutex progress_mutex;
  std::int64_t done = 0;
  const std::int64_t blocks = (n + kBlock - 1) / kBlock;
  JobPool pool(threads);
  pool.run(static_cast<int>(blocks), [&](int b) {
    const std::int64_t first = static_cast<std::int64_t>(b) * kBlock;
    const std::int64_t last = std::min(n, first + kBlock);
    for (std::int64_t k = first; k < last; ++k) {
      const std::int64_t sample = range.begin + k;
      RandomStream rng(spec.seed, stream, static_cast<std::uint64_t>(sample));
      evaluate(sample, rng, std::span<double>(r.values.data() + static_cast<std::size_t>(k) * w, w));
      if (progress) {
        const std::lock_guard lock(progress_mutex);
        progress(++done);
      }
    }
  });
  return r;
}

void writeSweepResults(const SweepResults& results, const std::filesystem::path& file) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot open for writing");
  const SweepSpec& s = results.spec;
  out << kMagic << ' ' << kFormatVersion << '\n'
      << "name " << s.name << '\n'
      << "samples " << s.samples << '\n'
      << "seed " << s.seed << '\n';
  char hash[32];
  std::snprintf(hash, sizeof hash, "%016" PRIx64, s.input_hash);
  out << "input_hash " << hash << '\n'
      << "values_per_sample " << s.values_per_sample << '\n'
      << "shard " << shardName(results.shard) << '\n'
      << "rows " << results.sample.size() << '\n';
  char buf[64];
  for (std::size_t i = 0; i < results.sample.size(); ++i) {
    out << results.sample[i];
    for (const double v : results.row(i)) {
      std::snprintf(buf, sizeof buf, " %a", v);  // exact: hexadecimal float
      out << buf;
    }
    out << '\n';
  }
  out.close();
  if (!out) throw std::runtime_error(file.string() + ": write failed");
}

SweepResults readSweepResults(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ConfigError(file, "", "cannot open the sweep results file");
  SweepResults r;
  r.source = file;
  int line_no = 0;
  std::string line;
  const auto fail = [&](const std::string& key, const std::string& why) { throw ConfigError(file, key, why, line_no); };
  const auto header = [&](std::string_view key) -> std::string {
    ++line_no;
    if (!std::getline(in, line)) fail(std::string(key), "the file ends before its header does");
    const std::string prefix = std::string(key) + " ";
    if (line.rfind(prefix, 0) != 0) fail(std::string(key), "expected '" + prefix + "...', found '" + line + "'");
    return line.substr(prefix.size());
  };
  if (header(kMagic) != std::to_string(kFormatVersion)) {
    fail(std::string(kMagic), "not a version " + std::to_string(kFormatVersion) + " sweep results file");
  }
  r.spec.name = header("name");
  std::int64_t v = 0;
  if (!parseInt(header("samples"), r.spec.samples)) fail("samples", "'" + line + "' is not an integer");
  if (!parseU64(header("seed"), r.spec.seed)) fail("seed", "'" + line + "' is not an unsigned integer");
  if (!parseU64(header("input_hash"), r.spec.input_hash, 16)) fail("input_hash", "'" + line + "' is not hexadecimal");
  if (!parseInt(header("values_per_sample"), v) || v < 1 || v > 1'000'000) {
    fail("values_per_sample", "'" + line + "': expected a positive integer");
  }
  r.spec.values_per_sample = static_cast<int>(v);
  try {
    r.shard = parseShardSpec(header("shard"));
  } catch (const ConfigError& e) {
    fail("shard", e.message());
  }
  std::int64_t rows = 0;
  if (!parseInt(header("rows"), rows) || rows < 0) fail("rows", "'" + line + "': expected a count");
  try {
    validateSweepSpec(r.spec);
  } catch (const ConfigError& e) {
    fail(e.keyPath(), e.message());
  }
  const auto w = static_cast<std::size_t>(r.spec.values_per_sample);
  r.sample.reserve(static_cast<std::size_t>(rows));
  r.values.reserve(static_cast<std::size_t>(rows) * w);
  for (std::int64_t k = 0; k < rows; ++k) {
    ++line_no;
    if (!std::getline(in, line)) fail("rows", "the file ends after " + std::to_string(k) + " of " + std::to_string(rows) + " rows");
    std::istringstream row(line);
    std::string token;
    row >> token;
    std::int64_t sample = 0;
    if (!parseInt(token, sample)) fail("sample", "'" + token + "' is not a sample number");
    r.sample.push_back(sample);
    for (std::size_t j = 0; j < w; ++j) {
      if (!(row >> token)) fail("values", "sample " + std::to_string(sample) + " has fewer than " + std::to_string(w) + " values");
      char* end = nullptr;
      const double x = std::strtod(token.c_str(), &end);
      if (end != token.c_str() + token.size()) fail("values", "'" + token + "' is not a number");
      r.values.push_back(x);
    }
    if (row >> token) fail("values", "sample " + std::to_string(sample) + " has more than " + std::to_string(w) + " values");
  }
  ++line_no;
  if (std::getline(in, line) && !line.empty()) fail("rows", "more lines than the " + std::to_string(rows) + " rows announced");
  return r;
}

SweepResults mergeSweepResults(const std::vector<SweepResults>& shards) {
  if (shards.empty()) throw ConfigError({}, "shards", "no shard to merge");
  const SweepResults& first = shards.front();
  const SweepSpec& spec = first.spec;
  const int count = first.shard.count;
  const auto mismatch = [&](const SweepResults& s, const std::string& field, const std::string& got,
                            const std::string& want) {
    throw ConfigError(s.source, field,
                      describe(s) + " is of another sweep: " + field + " " + got + ", but " + describe(first) + " has " + want);
  };
  std::vector<const SweepResults*> by_index(static_cast<std::size_t>(count), nullptr);
  for (const SweepResults& s : shards) {
    if (s.spec.name != spec.name) mismatch(s, "name", s.spec.name, spec.name);
    if (s.spec.samples != spec.samples) mismatch(s, "samples", std::to_string(s.spec.samples), std::to_string(spec.samples));
    if (s.spec.seed != spec.seed) mismatch(s, "seed", std::to_string(s.spec.seed), std::to_string(spec.seed));
    if (s.spec.input_hash != spec.input_hash) {
      mismatch(s, "input_hash", std::to_string(s.spec.input_hash), std::to_string(spec.input_hash));
    }
    if (s.spec.values_per_sample != spec.values_per_sample) {
      mismatch(s, "values_per_sample", std::to_string(s.spec.values_per_sample), std::to_string(spec.values_per_sample));
    }
    if (s.shard.count != count) mismatch(s, "shard count", std::to_string(s.shard.count), std::to_string(count));
    const SampleRange range = shardRange(spec.samples, s.shard);
    const SweepResults*& slot = by_index[static_cast<std::size_t>(s.shard.index - 1)];
    if (slot != nullptr) {
      throw ConfigError(s.source, "shard", describe(s) + " is given twice (also " + describe(*slot) + ")");
    }
    slot = &s;
    const auto w = static_cast<std::size_t>(spec.values_per_sample);
    if (s.values.size() != s.sample.size() * w) {
      throw ConfigError(s.source, "values", describe(s) + " holds " + std::to_string(s.values.size()) +
                                                " values for " + std::to_string(s.sample.size()) + " samples");
    }
    // Every sample of its range exactly once, in order.
    if (static_cast<std::int64_t>(s.sample.size()) != range.end - range.begin) {
      throw ConfigError(s.source, "samples", describe(s) + " holds " + std::to_string(s.sample.size()) +
                                                 " samples, its range [" + std::to_string(range.begin) + ", " +
                                                 std::to_string(range.end) + ") has " +
                                                 std::to_string(range.end - range.begin));
    }
    for (std::size_t k = 0; k < s.sample.size(); ++k) {
      if (s.sample[k] != range.begin + static_cast<std::int64_t>(k)) {
        throw ConfigError(s.source, "samples", describe(s) + ": expected sample " +
                                                   std::to_string(range.begin + static_cast<std::int64_t>(k)) +
                                                   " at row " + std::to_string(k) + ", found " + std::to_string(s.sample[k]) +
                                                   " (each sample of the shard's range once, in order)");
      }
    }
  }
  SweepResults whole;
  whole.spec = spec;
  whole.shard = {1, 1};
  for (int i = 0; i < count; ++i) {
    const SweepResults* s = by_index[static_cast<std::size_t>(i)];
    if (s == nullptr) {
      const SampleRange range = shardRange(spec.samples, {i + 1, count});
      throw ConfigError({}, "shards", "shard " + shardName({i + 1, count}) + " is missing (samples [" +
                                          std::to_string(range.begin) + ", " + std::to_string(range.end) + "))");
    }
    whole.sample.insert(whole.sample.end(), s->sample.begin(), s->sample.end());
    whole.values.insert(whole.values.end(), s->values.begin(), s->values.end());
  }
  return whole;
}

}  // namespace fullarm::core
