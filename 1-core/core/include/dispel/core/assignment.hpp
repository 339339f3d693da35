#pragma once
/// @file
/// Minimum-cost assignment (the Hungarian method), used to match objects to tracks.

#include <vector>

namespace dispel {

/// Solves the square assignment problem: picks one column per row, each column once, so that the
/// sum of cost[row * n + column] is smallest. Costs must be finite; forbid a pair by giving it a
/// cost larger than any sum of allowed ones. Returns the column of each row. O(n^3) time.
std::vector<int> min_cost_assignment(const std::vector<double>& cost, int n);

/// The same for @p rows <= @p cols: one column per row, each column at most once, the sum of
/// cost[row * cols + column] smallest; columns no row takes cost nothing. O(rows^2 x cols) time:
/// matching a few objects against many tracks, it is not paid for the tracks left over.
std::vector<int> min_cost_assignment(const std::vector<double>& cost, int rows, int cols);

}  // namespace dispel
