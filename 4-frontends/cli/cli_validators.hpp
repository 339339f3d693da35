#pragma once
/// @file
/// Checks of numeric options with a readable message (CLI11's PositiveNumber states its bound as
/// the 309 digits of the largest double).

#include <CLI/CLI.hpp>
#include <cmath>
#include <string>

namespace dispel::apps {

/// A finite number above @p bound (or at least @p bound when @p inclusive).
inline CLI::Validator finite_number_from(double bound, bool inclusive) {
  const std::string relation = inclusive ? ">= " : "> ";
  std::string shown = std::to_string(bound);
  shown.erase(shown.find_last_not_of('0') + 1);
  if (!shown.empty() && shown.back() == '.') shown.pop_back();
  return CLI::Validator(
      [bound, inclusive, relation, shown](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v) ||
            (inclusive ? v < bound : v <= bound)) {
          return "must be a finite number " + relation + shown + ", got " + text.substr(0, 40);
        }
        return {};
      },
      "NUMBER " + relation + shown);
}

/// A finite number > 0.
inline CLI::Validator positive_number() { return finite_number_from(0.0, false); }
/// A finite number >= 0.
inline CLI::Validator non_negative_number() { return finite_number_from(0.0, true); }

}  // namespace dispel::apps
