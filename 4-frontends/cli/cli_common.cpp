#include "cli_common.hpp"

#include <signal.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <set>
#include <vector>

#include "dispel/io/text.hpp"
#include "dispel/jobs/job.hpp"

namespace dispel::apps {
namespace {

// The options that name files, by their long (or positional) name, across all commands.
const std::set<std::string>& input_options() {
  static const std::set<std::string> names = {
      "input",      "scenario",     "--config",  "--truth",         "--result",
      "--estimate", "--wheels-csv", "--imu-csv", "--engine-config", "--map"};
  return names;
}
const std::set<std::string>& output_options() {
  static const std::set<std::string> names = {"--output", "--stats",    "--truth-csv",
                                              "--plot",   "--save-map", "--odom-csv"};
  return names;
}

// `eval-trajectory --truth` and `eval --truth` read; `odom --truth-csv` writes (listed above).
bool names_a_file(const std::string& name) {
  return input_options().count(name) != 0 || output_options().count(name) != 0;
}

// A value that reads as a number in full but is NaN or infinite ("nan", "-inf", "1e999").
bool non_finite_number(const std::string& text) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  return end != nullptr && *end == '\0' && end != text.c_str() && !std::isfinite(v);
}

std::atomic<bool> g_interrupted{false};
struct sigaction g_previous_int {
}, g_previous_term{};

extern "C" void on_interrupt(int) { g_interrupted.store(true); }

}  // namespace

void check_command_line(const CLI::App& command) {
  std::vector<jobs::FileArgument> inputs, outputs;
  for (const CLI::Option* opt : command.get_options()) {
    if (opt->count() == 0) continue;
    const std::string name = opt->get_name();
    for (const std::string& value : opt->results()) {
      if (!names_a_file(name) && non_finite_number(value)) {
        throw UsageError(name + ": " + io::quote(value) + " is not a finite number");
      }
      // A positional input is named by its path alone ("the input 'in.bag'").
      const bool positional = name.rfind("-", 0) != 0;
      if (input_options().count(name) != 0) inputs.push_back({positional ? "" : name, value});
      if (output_options().count(name) != 0) {
        outputs.push_back({name == "--output" ? "-o" : name, value});
      }
    }
  }
  jobs::check_files(inputs, outputs);
}

std::string error_line(const std::string& what) { return io::one_line(what, 400); }

Interrupts::Interrupts() {
  g_interrupted.store(false);
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  ::sigaction(SIGINT, &action, &g_previous_int);
  ::sigaction(SIGTERM, &action, &g_previous_term);
}

Interrupts::~Interrupts() {
  ::sigaction(SIGINT, &g_previous_int, nullptr);
  ::sigaction(SIGTERM, &g_previous_term, nullptr);
}

const std::atomic<bool>* Interrupts::flag() const { return &g_interrupted; }

}  // namespace dispel::apps
