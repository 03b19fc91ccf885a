// Run by CTest under `mpirun -np 2`: every rank takes part in the sweep, rank 0 checks the
// gathered results against the same sweep computed in one process.
#include "fullarm/mpi/mpi_sweep.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace fullarm::mpi {
namespace {

const Session* g_session = nullptr;

core::SweepSpec spec() {
  core::SweepSpec s;
  s.name = "mpi_sweep_test";
  s.samples = 1001;
  s.seed = 7;
  s.input_hash = core::sweepInputHash("mpi sweep test");
  s.values_per_sample = 2;
  return s;
}

void evaluate(std::int64_t sample, core::RandomStream& rng, std::span<double> out) {
  out[0] = rng.uniform01();
  out[1] = std::cos(static_cast<double>(sample)) * rng.uniform(-2.0, 2.0);
}

TEST(MpiSweep, RunsOnTwoRanks) { EXPECT_EQ(g_session->size(), 2); }

TEST(MpiSweep, RankZeroGathersTheSingleProcessResults) {
  const core::SweepResults spread = runSweepOverRanks(*g_session, spec(), evaluate, 2);
  if (g_session->rank() != 0) {
    const core::SampleRange range = core::shardRange(spec().samples, {g_session->rank() + 1, g_session->size()});
    ASSERT_FALSE(spread.sample.empty());
    EXPECT_EQ(spread.sample.front(), range.begin);
    EXPECT_EQ(spread.sample.back(), range.end - 1);
    return;
  }
  const core::SweepResults alone = core::runSweep(spec(), {1, 1}, evaluate, 1);
  EXPECT_EQ(spread.shard.count, 1);
  EXPECT_EQ(spread.sample, alone.sample);
  ASSERT_EQ(spread.values.size(), alone.values.size());
  for (std::size_t i = 0; i < alone.values.size(); ++i) ASSERT_EQ(spread.values[i], alone.values[i]) << "value " << i;
}

TEST(MpiSweep, AFailureOnOneRankReachesEveryRank) {
  const auto failing = [](std::int64_t sample, core::RandomStream&, std::span<double>) {
    if (sample == 900) throw std::invalid_argument("sample 900");  // in rank 1's shard
  };
  if (g_session->rank() == 1) {
    EXPECT_THROW((void)runSweepOverRanks(*g_session, spec(), failing, 1), std::invalid_argument);
  } else {
    try {
      (void)runSweepOverRanks(*g_session, spec(), failing, 1);
      ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("rank 1 failed"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace fullarm::mpi

int main(int argc, char** argv) {
  fullarm::mpi::Session session(argc, argv);
  fullarm::mpi::g_session = &session;
  ::testing::InitGoogleTest(&argc, argv);
  if (session.rank() != 0) {
    // One rank prints; every rank's failures still set its exit code, which mpirun reports.
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int failed = RUN_ALL_TESTS();
  int any_failed = 0;
  MPI_Allreduce(&failed, &any_failed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  return any_failed;
}
