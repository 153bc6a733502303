#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "dynamap/core/rounding.hpp"

namespace dynamap {
namespace {

// The inline rounding must be std::lround exactly: it replaced it where results are compared bit
// for bit (voxel keys, pixel lookups).
TEST(Rounding, RoundHalfAwayIsStdLroundForDoublesAndFloats) {
  std::vector<double> values;
  for (int k = -2000; k <= 2000; ++k) {
    const double half = k + 0.5;
    values.insert(values.end(), {half, std::nextafter(half, 0.0), std::nextafter(half, 1e9),
                                 std::nextafter(half, -1e9), static_cast<double>(k)});
  }
  values.insert(values.end(), {0.49999999999999994, -0.49999999999999994, 2147483647.5,
                               -2147483648.5, 2147483648.0, 3e9, -3e9, 4.5e15, -0.0});
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> any(-1e7, 1e7);
  for (int i = 0; i < 100000; ++i) values.push_back(any(rng));
  for (const double x : values) EXPECT_EQ(roundHalfAway(x), std::lround(x)) << x;
  for (const double x : values) {
    const auto f = static_cast<float>(x);
    EXPECT_EQ(roundHalfAway(f), std::lround(f)) << f;
    EXPECT_EQ(roundHalfAway(std::nextafter(f, 0.0f)), std::lround(std::nextafter(f, 0.0f))) << f;
  }
}

}  // namespace
}  // namespace dynamap
