#pragma once
/// @file
/// A core sweep spread over the processes of an MPI job (`mpirun -np N fullarm ...`): process r
/// runs shard r+1 of N on its own job pool, and process 0 gathers the shards and merges them with
/// core::mergeSweepResults, so the results are the ones a single process computes. Only programs
/// that link `fullarm::mpi` depend on MPI; core and the other modules do not.
/// Offline, not @rt.

#include <cstdint>
#include <functional>

#include "fullarm/core/sweep.hpp"

namespace fullarm::mpi {

/// MPI for the lifetime of the object: initialises MPI (thread level MPI_THREAD_FUNNELED: only
/// the thread that made the session calls MPI) and finalises it on destruction. Make one, in
/// main(), before any other MPI call; not copyable.
class Session {
 public:
  /// @throws std::runtime_error when MPI cannot be initialised or was initialised already.
  Session(int& argc, char**& argv);
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  ~Session();

  /// This process's rank in MPI_COMM_WORLD (0 gathers).
  [[nodiscard]] int rank() const noexcept { return rank_; }
  /// Number of processes in MPI_COMM_WORLD.
  [[nodiscard]] int size() const noexcept { return size_; }

 private:
  int rank_ = 0;
  int size_ = 1;
};

/// Runs `spec` over the processes of MPI_COMM_WORLD: each runs its shard (rank + 1 of size) with
/// `threads` workers, then rank 0 gathers every shard. Collective: every rank calls it with the
/// same spec. A rank whose samples throw still takes part in the gather and then rethrows; the
/// other ranks then get a std::runtime_error naming the failed rank.
/// @return on rank 0, the whole sweep (shard 1/1); on the other ranks, their own shard.
[[nodiscard]] core::SweepResults runSweepOverRanks(const Session& session, const core::SweepSpec& spec,
                                                   const core::SweepFunction& evaluate, int threads,
                                                   const std::function<void(std::int64_t done)>& progress = {});

}  // namespace fullarm::mpi
