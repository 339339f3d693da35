#include "dispel/core/assignment.hpp"

#include <cassert>
#include <limits>

namespace dispel {

// Shortest augmenting paths with row and column potentials (Kuhn-Munkres in the O(n^3) form).
// Rows are added one at a time; Dijkstra over reduced costs finds the cheapest way to place it.
std::vector<int> min_cost_assignment(const std::vector<double>& cost, int n) {
  return min_cost_assignment(cost, n, n);
}

std::vector<int> min_cost_assignment(const std::vector<double>& cost, int rows, int cols) {
  assert(rows <= cols && static_cast<int>(cost.size()) == rows * cols);
  const int n = cols;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // 1-based with a virtual column 0 holding the row being placed.
  std::vector<double> u(rows + 1, 0.0);
  std::vector<double> v(n + 1, 0.0);
  std::vector<int> row_of(n + 1, 0);
  std::vector<int> way(n + 1, 0);
  std::vector<double> min_reduced(n + 1);
  std::vector<char> used(n + 1);
  for (int row = 1; row <= rows; ++row) {
    row_of[0] = row;
    int col0 = 0;
    min_reduced.assign(n + 1, kInf);
    used.assign(n + 1, 0);
    do {
      used[col0] = 1;
      const int r = row_of[col0];
      double delta = kInf;
      int col1 = 0;
      for (int col = 1; col <= n; ++col) {
        if (used[col]) continue;
        const double reduced = cost[(r - 1) * n + (col - 1)] - u[r] - v[col];
        if (reduced < min_reduced[col]) {
          min_reduced[col] = reduced;
          way[col] = col0;
        }
        if (min_reduced[col] < delta) {
          delta = min_reduced[col];
          col1 = col;
        }
      }
      for (int col = 0; col <= n; ++col) {
        if (used[col]) {
          u[row_of[col]] += delta;
          v[col] -= delta;
        } else {
          min_reduced[col] -= delta;
        }
      }
      col0 = col1;
    } while (row_of[col0] != 0);
    do {  // Flip the augmenting path.
      const int col1 = way[col0];
      row_of[col0] = row_of[col1];
      col0 = col1;
    } while (col0 != 0);
  }
  std::vector<int> column_of_row(rows, -1);
  for (int col = 1; col <= n; ++col) {
    if (row_of[col] != 0) column_of_row[row_of[col] - 1] = col - 1;
  }
  return column_of_row;
}

}  // namespace dispel
