#pragma once
/// @file
/// What every dispel command shares around its job: the checks of the command line before any
/// work (files and numbers, docs/cli.md#reliability), cancellation on Ctrl-C, and the one line an
/// error becomes on stderr.

#include <CLI/CLI.hpp>
#include <atomic>
#include <exception>
#include <stdexcept>
#include <string>

namespace dispel::apps {

/// The exit code of a command line that cannot be run as given (an unknown option, a missing or
/// bad value); other errors exit 1, an interruption 130.
inline constexpr int kUsageExitCode = 2;

/// A command line that cannot be run as given: exit kUsageExitCode.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Checks the options given to @p command before it runs: every number is finite (UsageError
/// naming the option), and its files (inputs: the positional input or scenario, --config,
/// --truth, ...; outputs: -o, --stats, --truth-csv, ...) pass jobs::check_files (JobError).
void check_command_line(const CLI::App& command);

/// @p what as one printable line of at most a few hundred characters (see io::one_line).
std::string error_line(const std::string& what);

/// While alive, SIGINT and SIGTERM set flag() instead of ending the program (the job then stops
/// and removes what it started writing). The handlers before are restored at destruction.
class Interrupts {
 public:
  Interrupts();
  ~Interrupts();
  Interrupts(const Interrupts&) = delete;
  Interrupts& operator=(const Interrupts&) = delete;

  const std::atomic<bool>* flag() const;
  bool interrupted() const { return flag()->load(); }
};

}  // namespace dispel::apps
