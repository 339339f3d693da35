#include "dispel/core/integer_key_map.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <unordered_map>

namespace dispel {
namespace {

// Keys as the registration makes them: two signed 32-bit cell indices side by side.
std::uint64_t cell_key(std::int32_t ix, std::int32_t iy) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ix)) << 32U) |
         static_cast<std::uint32_t>(iy);
}

TEST(IntegerKeyMap, FindsWhatWasInsertedAndNothingElse) {
  IntegerKeyMap<int> map;
  EXPECT_TRUE(map.empty());
  EXPECT_EQ(map.find(cell_key(0, 0)), nullptr);
  for (std::int32_t x = -40; x < 40; ++x) {
    for (std::int32_t y = -40; y < 40; ++y) map[cell_key(x, y)] = x * 1000 + y;
  }
  ASSERT_EQ(map.size(), 6400U);
  for (std::int32_t x = -40; x < 40; ++x) {
    for (std::int32_t y = -40; y < 40; ++y) {
      const int* v = map.find(cell_key(x, y));
      ASSERT_NE(v, nullptr) << x << " " << y;
      EXPECT_EQ(*v, x * 1000 + y);
    }
  }
  EXPECT_EQ(map.find(cell_key(40, 0)), nullptr);
  EXPECT_EQ(map.find(cell_key(0, -41)), nullptr);
  // operator[] on a present key neither inserts nor resets.
  map[cell_key(-3, 7)] += 1;
  EXPECT_EQ(map.size(), 6400U);
  const int* changed = map.find(cell_key(-3, 7));
  ASSERT_NE(changed, nullptr);
  EXPECT_EQ(*changed, -3000 + 7 + 1);
  map.clear();
  EXPECT_TRUE(map.empty());
  EXPECT_EQ(map.find(cell_key(-3, 7)), nullptr);
  map[cell_key(1, 1)] = 5;
  const int* again = map.find(cell_key(1, 1));
  ASSERT_NE(again, nullptr);
  EXPECT_EQ(*again, 5);
}

TEST(IntegerKeyMap, EraseIfKeepsTheRestFindable) {
  IntegerKeyMap<int> map;
  for (std::int32_t x = 0; x < 100; ++x) map[cell_key(x, -x)] = x;
  map.erase_if([](std::uint64_t /*key*/, const int& v) { return v % 3 == 0; });
  EXPECT_EQ(map.size(), 66U);
  for (std::int32_t x = 0; x < 100; ++x) {
    const int* v = map.find(cell_key(x, -x));
    if (x % 3 == 0) {
      EXPECT_EQ(v, nullptr) << x;
    } else {
      ASSERT_NE(v, nullptr) << x;
      EXPECT_EQ(*v, x);
    }
  }
  map.erase_if([](std::uint64_t /*key*/, const int& /*v*/) { return true; });
  EXPECT_TRUE(map.empty());
  EXPECT_EQ(map.find(cell_key(1, -1)), nullptr);
}

// A random sequence of insertions, lookups and erasures (keys drawn from a small range, so that
// they repeat and collide) agrees with std::unordered_map at every step.
TEST(IntegerKeyMap, AgreesWithTheStandardMapOnRandomOperations) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::int32_t> cell(-60, 60);
  std::uniform_int_distribution<int> op(0, 99);
  IntegerKeyMap<int> map;
  std::unordered_map<std::uint64_t, int> reference;
  for (int step = 0; step < 200000; ++step) {
    const std::uint64_t key = cell_key(cell(rng), cell(rng));
    const int what = op(rng);
    if (what < 45) {
      map[key] += step;
      reference[key] += step;
    } else if (what < 99) {
      const int* v = map.find(key);
      const auto it = reference.find(key);
      ASSERT_EQ(v == nullptr, it == reference.end()) << step;
      if (v != nullptr) {
        ASSERT_EQ(*v, it->second) << step;
      }
    } else {
      const auto cut = static_cast<std::uint64_t>(step % 7);
      map.erase_if([cut](std::uint64_t k, const int& /*v*/) { return k % 7 == cut; });
      for (auto it = reference.begin(); it != reference.end();) {
        it = it->first % 7 == cut ? reference.erase(it) : std::next(it);
      }
    }
    ASSERT_EQ(map.size(), reference.size()) << step;
  }
  for (const auto& [key, value] : reference) {
    const int* v = map.find(key);
    ASSERT_NE(v, nullptr);
    EXPECT_EQ(*v, value);
  }
}

}  // namespace
}  // namespace dispel
