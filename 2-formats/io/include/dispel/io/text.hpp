#pragma once
/// @file
/// Text from the outside world, made safe to read and to echo: the files that dispel reads whole
/// (configurations, scenarios) and the words an error message quotes.

#include <cstddef>
#include <string>
#include <string_view>

namespace dispel::io {

/// True when @p text ends in @p suffix (a file name's extension, say), as written.
inline bool ends_with(std::string_view text, std::string_view suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// How many characters of an input quote() keeps by default.
inline constexpr std::size_t kQuotedChars = 80;

/// @p text in single quotes for an error message: bytes that are not printable ASCII written as
/// \xNN, cut after @p max_chars characters (as written: an escaped byte counts 4) with
/// "... (N bytes)" telling the whole length. An error never echoes unbounded or binary input.
std::string quote(std::string_view text, std::size_t max_chars = kQuotedChars);

/// @p text made one printable line of at most @p max_chars characters (for a whole message):
/// newlines and other control bytes escaped (an escaped byte counts 4), the rest cut with "...".
std::string one_line(std::string_view text, std::size_t max_chars = 400);

/// Reads the whole of @p path, which must be a regular file: its type is checked (stat) before
/// it is opened, so a directory is refused and a FIFO never blocks. @p what names the file in
/// errors ("configuration file", "scenario file"). @throws ConfigError "<path>: cannot open the
/// <what> (<reason>)", "<path>: the <what> is not a regular file (a directory)"
std::string read_regular_file(const std::string& path, const std::string& what);

}  // namespace dispel::io
