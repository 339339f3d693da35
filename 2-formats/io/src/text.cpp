#include "dispel/io/text.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "dispel/io/errors.hpp"

namespace dispel::io {
namespace {

void append_escaped(std::string& out, unsigned char c) {
  if (c >= 0x20 && c < 0x7f) {
    out.push_back(static_cast<char>(c));
    return;
  }
  char hex[8];
  std::snprintf(hex, sizeof hex, "\\x%02x", c);
  out += hex;
}

// As much of @p text, escaped, as fits in @p max_chars characters (an escaped byte takes 4: they
// are counted as written, not as read); whether it was cut.
std::string escaped_prefix(std::string_view text, std::size_t max_chars, bool& cut) {
  std::string out;
  std::size_t i = 0;
  for (; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    const std::size_t width = c >= 0x20 && c < 0x7f ? 1 : 4;
    if (out.size() + width > max_chars) break;
    append_escaped(out, c);
  }
  cut = i < text.size();
  return out;
}

const char* file_type(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a plain file";
}

}  // namespace

std::string quote(std::string_view text, std::size_t max_chars) {
  bool cut = false;
  std::string out = "'" + escaped_prefix(text, max_chars, cut) + "'";
  if (cut) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

std::string one_line(std::string_view text, std::size_t max_chars) {
  bool cut = false;
  std::string out = escaped_prefix(text, max_chars, cut);
  if (cut) out += "...";
  return out;
}

std::string read_regular_file(const std::string& path, const std::string& what) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw ConfigError(path + ": cannot open the " + what + " (" + std::strerror(errno) + ")");
  }
  if (!S_ISREG(st.st_mode)) {
    throw ConfigError(path + ": the " + what + " is not a regular file (" + file_type(st.st_mode) +
                      ")");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw ConfigError(path + ": cannot open the " + what + " (" + std::strerror(errno) + ")");
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError(path + ": cannot read the " + what);
  return text.str();
}

}  // namespace dispel::io
