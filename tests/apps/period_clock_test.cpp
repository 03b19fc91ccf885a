// The pacing of a real board's reads (PeriodClock): a late wake-up is reported, counted and not
// made up for by a burst; a period that is not finite and positive is refused.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <thread>

#include "command_device.hpp"

namespace fullarm::app {
namespace {

TEST(PeriodClock, ALoopThatStallsPastHalfAPeriodIsReportedAndRestartsFromNow) {
  PeriodClock clock(1e-3);
  EXPECT_TRUE(clock());  // starts the clock
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  // The next deadline was 1 ms after the start; it is at least 4 ms past.
  EXPECT_FALSE(clock());
  EXPECT_EQ(clock.overruns(), 1);
  // No burst: the deadlines restarted from the late call, so the next call waits about a
  // period instead of returning at once for each of the periods missed.
  const auto before = std::chrono::steady_clock::now();
  (void)clock();
  const auto waited = std::chrono::steady_clock::now() - before;
  EXPECT_GE(waited, std::chrono::microseconds(300));  // a burst would return at once
}

TEST(PeriodClock, RefusesAPeriodThatIsNotFiniteAndPositive) {
  for (const double bad :
       {0.0, -1e-3, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(PeriodClock{bad}, std::invalid_argument) << bad;
  }
}

}  // namespace
}  // namespace fullarm::app
