#pragma once
/// @file
/// Writing a file so that it appears complete or not at all.

#include <string>

namespace dispel::io {

/// Reserves "<path>.partial" next to @p path for writing. commit() renames it to @p path;
/// destruction without commit() deletes it. A failure or an interruption never leaves a
/// half-written file under the final name. A path that names a device or a pipe (/dev/null,
/// /dev/stdout, a FIFO) is written in place: there is no file to replace.
class AtomicFile {
 public:
  explicit AtomicFile(std::string path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Where to write.
  const std::string& temp_path() const { return temp_; }
  /// Moves the finished file into place. @throws OutputError (errors.hpp) if the rename fails.
  void commit();

 private:
  std::string path_;
  std::string temp_;
  bool committed_ = false;
  bool direct_ = false;  ///< Written in place (a device or a pipe).
};

/// Writes @p text to @p path through an AtomicFile, checking every write, the flush and the
/// close. @throws OutputError "<path>: cannot write (<reason>)"; nothing is left behind then.
void write_file_atomically(const std::string& path, const std::string& text);

}  // namespace dispel::io
