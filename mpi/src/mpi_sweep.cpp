#include "fullarm/mpi/mpi_sweep.hpp"

#include <mpi.h>

#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

namespace fullarm::mpi {
namespace {

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed (code " + std::to_string(code) + ")");
}

}  // namespace

Session::Session(int& argc, char**& argv) {
  int initialised = 0;
  check(MPI_Initialized(&initialised), "MPI_Initialized");
  if (initialised != 0) throw std::runtime_error("MPI: already initialised (make one mpi::Session per program)");
  int provided = 0;
  check(MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  check(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(MPI_COMM_WORLD, &size_), "MPI_Comm_size");
}

Session::~Session() { MPI_Finalize(); }

core::SweepResults runSweepOverRanks(const Session& session, const core::SweepSpec& spec,
                                     const core::SweepFunction& evaluate, int threads,
                                     const std::function<void(std::int64_t done)>& progress) {
  const int rank = session.rank();
  const int size = session.size();
  core::SweepResults mine;
  std::exception_ptr error;
  try {
    mine = core::runSweep(spec, {rank + 1, size}, evaluate, threads, progress);
  } catch (...) {
    error = std::current_exception();
  }
  // Every rank reports whether it succeeded before any data moves, so no rank waits forever.
  const int ok = error ? 0 : 1;
  std::vector<int> oks(static_cast<std::size_t>(size));
  check(MPI_Gather(&ok, 1, MPI_INT, oks.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
  int first_failed = -1;
  if (rank == 0) {
    for (int r = 0; r < size; ++r) {
      if (oks[static_cast<std::size_t>(r)] == 0 && first_failed < 0) first_failed = r;
    }
  }
  check(MPI_Bcast(&first_failed, 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Bcast");
  if (error) std::rethrow_exception(error);
  if (first_failed >= 0) {
    throw std::runtime_error("sweep '" + spec.name + "': rank " + std::to_string(first_failed) + " failed");
  }

  const int rows = static_cast<int>(mine.sample.size());
  std::vector<int> row_counts(static_cast<std::size_t>(size));
  check(MPI_Gather(&rows, 1, MPI_INT, row_counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
  std::vector<core::SweepResults> shards;
  std::vector<int> sample_displ(static_cast<std::size_t>(size));
  std::vector<int> value_counts(static_cast<std::size_t>(size));
  std::vector<int> value_displ(static_cast<std::size_t>(size));
  std::vector<std::int64_t> all_samples;
  std::vector<double> all_values;
  if (rank == 0) {
    int s = 0;
    for (int r = 0; r < size; ++r) {
      const auto i = static_cast<std::size_t>(r);
      sample_displ[i] = s;
      value_counts[i] = row_counts[i] * spec.values_per_sample;
      value_displ[i] = s * spec.values_per_sample;
      s += row_counts[i];
    }
    all_samples.resize(static_cast<std::size_t>(s));
    all_values.resize(static_cast<std::size_t>(s) * static_cast<std::size_t>(spec.values_per_sample));
  }
  check(MPI_Gatherv(mine.sample.data(), rows, MPI_INT64_T, all_samples.data(), row_counts.data(), sample_displ.data(),
                    MPI_INT64_T, 0, MPI_COMM_WORLD),
        "MPI_Gatherv");
  check(MPI_Gatherv(mine.values.data(), static_cast<int>(mine.values.size()), MPI_DOUBLE, all_values.data(),
                    value_counts.data(), value_displ.data(), MPI_DOUBLE, 0, MPI_COMM_WORLD),
        "MPI_Gatherv");
  if (rank != 0) return mine;
  for (int r = 0; r < size; ++r) {
    const auto i = static_cast<std::size_t>(r);
    core::SweepResults shard;
    shard.spec = spec;
    shard.shard = {r + 1, size};
    const auto first = all_samples.begin() + sample_displ[i];
    shard.sample.assign(first, first + row_counts[i]);
    const auto vfirst = all_values.begin() + value_displ[i];
    shard.values.assign(vfirst, vfirst + value_counts[i]);
    shards.push_back(std::move(shard));
  }
  return core::mergeSweepResults(shards);  // checks every sample is present once
}

}  // namespace fullarm::mpi
