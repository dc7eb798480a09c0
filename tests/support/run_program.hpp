// Test helper: runs one of metro's programs through the shell and captures its exit code,
// standard output and standard error (the latter through a uniquely named file).
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace metro::testing {

struct ProgramRun {
  int exit_code = -1;  // -1 when the program did not exit normally or could not start.
  std::string out;
  std::string err;
};

// Runs `exe args` (args is shell text: quoting and redirections are the caller's).
inline ProgramRun RunProgram(const std::string& exe, const std::string& args) {
  static std::atomic<int> counter{0};
  const std::string err_path =
      "metro_run_err_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ".txt";
  const std::string cmd = exe + " " + args + " 2>" + err_path;
  ProgramRun r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) return r;
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) r.out.append(buffer, n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream err(err_path);
  std::stringstream ss;
  ss << err.rdbuf();
  r.err = ss.str();
  std::remove(err_path.c_str());
  return r;
}

}  // namespace metro::testing
