// For the tests that feed a core garbage and check that it never answers NaN or out of bounds:
// seeded numbers that are now and then one of the values that break arithmetic. Header-only;
// test code only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iterator>
#include <limits>
#include <random>

namespace follow_bot_common {

class GarbageNumbers {
 public:
  // NaN, both infinities, the largest finite values, zero and two tiny ones (one subnormal).
  static constexpr double kSpecials[] = {
      std::numeric_limits<double>::quiet_NaN(),  std::numeric_limits<double>::infinity(),
      -std::numeric_limits<double>::infinity(),  std::numeric_limits<double>::max(),
      std::numeric_limits<double>::lowest(),     0.0,
      std::numeric_limits<double>::denorm_min(), 1e-300};

  // maybe() answers a special `special_share` of the time.
  GarbageNumbers(std::uint32_t seed, double special_share)
      : random_(seed), special_share_(special_share) {}

  double uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(random_);
  }

  bool chance(double probability) { return uniform(0.0, 1.0) < probability; }

  // `normal`, or now and then one of kSpecials.
  double maybe(double normal) {
    if (!chance(special_share_)) return normal;
    std::uniform_int_distribution<std::size_t> pick(0, std::size(kSpecials) - 1);
    return kSpecials[pick(random_)];
  }

 private:
  std::mt19937 random_;
  double special_share_;
};

}  // namespace follow_bot_common
