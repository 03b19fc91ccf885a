#include "alloc_guard.hpp"

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace fullarm::testing {
namespace {

extern "C" {
void fullarmProbeMallocAndFree(std::size_t bytes);
std::size_t fullarmProbeNewString(std::size_t length);
}

TEST(AllocationGuard, TheProgramsAllocatorIsTheOneLibrariesCall) {
  EXPECT_TRUE(allocatorInterposed());
}

// malloc and operator new called from inside a shared library (not the test program) count.
TEST(AllocationGuard, CountsAllocationsInsideASharedLibrary) {
  AllocationGuard guard;
  fullarmProbeMallocAndFree(48);
  EXPECT_EQ(guard.allocations(), 1u);
  EXPECT_EQ(guard.bytes(), 48u);
  EXPECT_EQ(fullarmProbeNewString(200), 200u);
  EXPECT_EQ(guard.allocations(), 3u);  // the std::string object and its buffer
}

TEST(AllocationGuard, MacroFailsWhenASharedLibraryAllocates) {
  EXPECT_NONFATAL_FAILURE(EXPECT_NO_HEAP_ALLOCATION(fullarmProbeMallocAndFree(16)), "allocated 1 times");
}

// A real dependency: yaml-cpp's parser allocates inside libyaml-cpp.so.
TEST(AllocationGuard, CountsAllocationsOfYamlCpp) {
  AllocationGuard guard;
  const YAML::Node node = YAML::Load("joint: R_EB\nlimits: [-0.5, 2.1]\n");
  EXPECT_GE(guard.allocations(), 1u);
  EXPECT_EQ(node["joint"].as<std::string>(), "R_EB");
}

// The guard is armed per thread: another thread's allocations do not count.
TEST(AllocationGuard, CountsOnlyTheArmingThread) {
  AllocationGuard guard;
  std::thread other;
  const std::size_t before = guard.allocations();  // starting a thread may allocate here
  {
    // Allocations made by the other thread while this one waits.
    other = std::thread([] {
      for (int i = 0; i < 10; ++i) fullarmProbeMallocAndFree(32);
    });
  }
  const std::size_t after_start = guard.allocations();
  other.join();
  EXPECT_EQ(guard.allocations(), after_start);
  EXPECT_GE(after_start, before);
}

TEST(AllocationGuard, CountsOperatorNew) {
  AllocationGuard guard;
  auto p = std::make_unique<int>(3);
  EXPECT_EQ(guard.allocations(), 1u);
  EXPECT_GE(guard.bytes(), sizeof(int));
}

TEST(AllocationGuard, CountsVectorGrowth) {
  std::vector<double> v;
  AllocationGuard guard;
  v.push_back(1.0);
  EXPECT_GE(guard.allocations(), 1u);
}

TEST(AllocationGuard, CountsEigenDynamicMatrices) {
  AllocationGuard guard;
  Eigen::MatrixXd m = Eigen::MatrixXd::Identity(20, 20);
  EXPECT_GE(guard.allocations(), 1u);
  EXPECT_GE(guard.bytes(), 20u * 20u * sizeof(double));
  EXPECT_EQ(m(3, 3), 1.0);
}

TEST(AllocationGuard, CountsPlainMallocAndCalloc) {
  AllocationGuard guard;
  void* volatile a = std::malloc(64);
  void* volatile b = std::calloc(4, 16);
  std::free(a);
  std::free(b);
  EXPECT_EQ(guard.allocations(), 2u);
}

TEST(AllocationGuard, FixedSizeEigenDoesNotAllocate) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Random();
  Eigen::Vector3d x = Eigen::Vector3d::Ones();
  EXPECT_NO_HEAP_ALLOCATION(x = a * x);
}

TEST(AllocationGuard, StringBeyondSmallBufferIsCaught) {
  // The macro must fail for allocating code: check the guard count directly.
  AllocationGuard guard;
  std::string s(100, 'x');
  EXPECT_EQ(guard.allocations(), 1u);
  EXPECT_EQ(s.size(), 100u);
}

TEST(AllocationGuard, NestedGuardsCountIndependently) {
  AllocationGuard outer;
  auto a = std::make_unique<int>(1);
  {
    AllocationGuard inner;
    auto b = std::make_unique<int>(2);
    EXPECT_EQ(inner.allocations(), 1u);
  }
  EXPECT_EQ(outer.allocations(), 2u);
}

// Escapes through a volatile global so the optimiser cannot elide the new/delete pair.
double* volatile g_sink = nullptr;
void allocateOnce() {
  g_sink = new double(1.0);
  delete g_sink;
}

TEST(AllocationGuard, MacroReportsAllocatingStatement) {
  // EXPECT_NONFATAL_FAILURE checks that the macro really fails on an allocation.
  EXPECT_NONFATAL_FAILURE(EXPECT_NO_HEAP_ALLOCATION(allocateOnce()), "allocated 1 times");
}

}  // namespace
}  // namespace fullarm::testing
