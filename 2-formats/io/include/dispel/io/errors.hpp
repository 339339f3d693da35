#pragma once
/// @file
/// The errors of dispel's formats and conversions: each what() is one line that names the file
/// (and, where there is one, the key, line or topic) and the problem.

#include <stdexcept>

namespace dispel::io {

/// An input that cannot be used: a file that is missing, unreadable, truncated or malformed, or
/// a recording without what is asked of it.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A configuration that cannot be used (a YAML file or a node's parameters): an unknown key, a
/// wrong type, an invalid value.
class ConfigError : public InputError {
 public:
  using InputError::InputError;
};

/// An output that cannot be written (an unwritable path, a full disk).
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace dispel::io
