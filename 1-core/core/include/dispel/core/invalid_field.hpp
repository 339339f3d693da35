#pragma once
/// @file
/// The one way configuration checks report a bad value.

#include <sstream>
#include <stdexcept>
#include <string>

namespace dispel {

/// Throws std::invalid_argument("<field> must be <rule>, got <value>").
[[noreturn]] inline void reject_field(const std::string& field, double value, const char* rule) {
  std::ostringstream out;
  out << field << " must be " << rule << ", got " << value;
  throw std::invalid_argument(out.str());
}

}  // namespace dispel
