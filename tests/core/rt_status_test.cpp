// The real-time status keeps the first cause, accumulates the fault bits and never allocates.
#include "fullarm/core/rt_status.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <type_traits>

#include "alloc_guard.hpp"

namespace fullarm::core {
namespace {

static_assert(std::is_trivially_copyable_v<RtStatus>);

TEST(RtStatus, StartsOkAndKeepsTheFirstCauseWhileCollectingEveryFaultBit) {
  RtStatus s;
  EXPECT_TRUE(s.ok());
  EXPECT_STREQ(s.message, "ok");
  EXPECT_NO_HEAP_ALLOCATION({
    s.raise(RtCode::kBadInput, kFaultNonFiniteInput, "joint angle is not finite");
    s.raise(RtCode::kSolverFailure, kFaultStepTooSmall, "step too small");
  });
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.code, RtCode::kBadInput);
  EXPECT_STREQ(s.message, "joint angle is not finite");
  EXPECT_TRUE(s.has(kFaultNonFiniteInput));
  EXPECT_TRUE(s.has(kFaultStepTooSmall));
  EXPECT_FALSE(s.has(kFaultCapacity));
  EXPECT_EQ(s.faults, kFaultNonFiniteInput | kFaultStepTooSmall);
  s.clear();
  EXPECT_TRUE(s.ok());
  EXPECT_EQ(s.faults, kFaultNone);
}

TEST(RtStatus, EveryCodeHasAName) {
  for (RtCode c : {RtCode::kOk, RtCode::kNotConfigured, RtCode::kBadInput, RtCode::kBadState, RtCode::kSolverFailure}) {
    EXPECT_STRNE(rtCodeName(c), "unknown");
  }
  const RtStatus f = RtStatus::fault(RtCode::kNotConfigured, kFaultNotConfigured, "step before reset");
  EXPECT_EQ(f.code, RtCode::kNotConfigured);
  EXPECT_EQ(f.faults, kFaultNotConfigured);
  EXPECT_EQ(std::strcmp(rtCodeName(f.code), "not configured"), 0);
}

}  // namespace
}  // namespace fullarm::core
