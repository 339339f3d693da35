#include "dispel/core/assignment.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <set>

namespace dispel {
namespace {

double total(const std::vector<double>& cost, int n, const std::vector<int>& cols) {
  double sum = 0.0;
  for (int r = 0; r < n; ++r) sum += cost[r * n + cols[r]];
  return sum;
}

TEST(MinCostAssignment, MatchesBruteForceOnRandomMatrices) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 1 + trial % 7;
    std::vector<double> cost(n * n);
    for (double& c : cost) c = (u(rng) < 1.0) ? 1e6 : u(rng);  // Some forbidden pairs.
    const std::vector<int> cols = min_cost_assignment(cost, n);
    ASSERT_EQ(static_cast<int>(cols.size()), n);
    EXPECT_EQ(std::set<int>(cols.begin(), cols.end()).size(), static_cast<std::size_t>(n));
    std::vector<int> perm(n);
    std::iota(perm.begin(), perm.end(), 0);
    double best = 1e18;
    do {
      best = std::min(best, total(cost, n, perm));
    } while (std::next_permutation(perm.begin(), perm.end()));
    EXPECT_NEAR(total(cost, n, cols), best, 1e-9) << "trial " << trial;
  }
}

TEST(MinCostAssignment, RectangularMatchesBruteForceOnRandomMatrices) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  for (int trial = 0; trial < 300; ++trial) {
    const int rows = 1 + trial % 4, cols = rows + trial % 5;
    std::vector<double> cost(rows * cols);
    for (double& c : cost) c = (u(rng) < 1.0) ? 1e6 : u(rng);
    const std::vector<int> chosen = min_cost_assignment(cost, rows, cols);
    ASSERT_EQ(static_cast<int>(chosen.size()), rows);
    EXPECT_EQ(std::set<int>(chosen.begin(), chosen.end()).size(), static_cast<std::size_t>(rows));
    double sum = 0.0;
    for (int r = 0; r < rows; ++r) {
      ASSERT_GE(chosen[r], 0);
      ASSERT_LT(chosen[r], cols);
      sum += cost[r * cols + chosen[r]];
    }
    // Brute force: every way to give the rows distinct columns (permutations of the columns,
    // the first rows of each).
    std::vector<int> perm(cols);
    std::iota(perm.begin(), perm.end(), 0);
    double best = 1e18;
    do {
      double s = 0.0;
      for (int r = 0; r < rows; ++r) s += cost[r * cols + perm[r]];
      best = std::min(best, s);
    } while (std::next_permutation(perm.begin(), perm.end()));
    EXPECT_NEAR(sum, best, 1e-9) << "trial " << trial;
  }
}

TEST(MinCostAssignment, PrefersTheGlobalOptimumOverGreedyChoices) {
  // Greedy takes (0,0) = 1 and is left with (1,1) = 100; the optimum is 2 + 3.
  const std::vector<double> cost = {1, 2, 3, 100};
  EXPECT_EQ(min_cost_assignment(cost, 2), (std::vector<int>{1, 0}));
}

}  // namespace
}  // namespace dispel
