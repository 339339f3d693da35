#pragma once
// For the ROS 2 live tests: a dispel-ros2 node as a child process, its stderr in a file.
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "live_test_support.hpp"
#include "test_files.hpp"

extern char** environ;

namespace dispel::ros2::live_test {

class NodeProcess {
 public:
  /// `dispel-ros2 COMMAND --ros-args --params-file <params> -r __node:=NAME` with
  /// ROS_DOMAIN_ID=@p domain and the test's environment.
  NodeProcess(const std::string& command, const std::string& params, const std::string& name,
              int domain)
      : log_(dispel::test::temp_path(name + ".log")) {
    // Everything the child needs is made before fork: the child only opens, dups and execs.
    const std::string params_path = dispel::test::write_text(name + ".yaml", params);
    std::vector<std::string> args = {DISPEL_ROS2_EXECUTABLE, command,     "--ros-args",
                                     "--params-file",        params_path, "-r",
                                     "__node:=" + name};
    std::vector<std::string> env = {"ROS_DOMAIN_ID=" + std::to_string(domain)};
    for (char** e = environ; *e != nullptr; ++e) {
      if (std::string(*e).rfind("ROS_DOMAIN_ID=", 0) != 0) env.emplace_back(*e);
    }
    std::vector<char*> argv, envp;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    for (std::string& e : env) envp.push_back(e.data());
    envp.push_back(nullptr);
    pid_ = ::fork();
    if (pid_ == 0) {
      // A test that dies (an abort, a sanitizer) takes its node with it, and the node holds
      // none of the test's output pipes: nothing is left to keep ctest waiting.
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      const int fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::execve(argv[0], argv.data(), envp.data());
      ::_exit(127);
    }
  }
  ~NodeProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  NodeProcess(const NodeProcess&) = delete;
  NodeProcess& operator=(const NodeProcess&) = delete;

  /// @p signal (SIGTERM, or SIGINT as Ctrl-C sends it), then its exit status (-1: it did not stop
  /// within kWaitS).
  int stop(int signal = SIGTERM) {
    ::kill(pid_, signal);
    int status = 0;
    const bool exited = eventually([&] { return ::waitpid(pid_, &status, WNOHANG) == pid_; });
    if (!exited) return -1;
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  std::string log() const { return dispel::test::read_bytes(log_); }

 private:
  std::string log_;
  pid_t pid_ = -1;
};

}  // namespace dispel::ros2::live_test
