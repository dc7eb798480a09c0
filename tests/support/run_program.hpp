// Test helper: runs one of metro's programs through the shell and captures its exit code,
// standard output and standard error (the latter through a uniquely named file), optionally
// feeding its standard input.
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

namespace run_program_internal {

inline std::string UniqueName(const std::string& what) {
  static std::atomic<int> counter{0};
  return "metro_run_" + what + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) +
         ".txt";
}

// Runs the shell command `cmd` with stderr to a file; stdout through a pipe.
inline ProgramRun RunShell(const std::string& cmd) {
  const std::string err_path = UniqueName("err");
  ProgramRun r;
  FILE* pipe = ::popen((cmd + " 2>" + err_path).c_str(), "r");
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

}  // namespace run_program_internal

// Runs `exe args` (args is shell text: quoting and redirections are the caller's). The
// program's stdin is the test's own.
inline ProgramRun RunProgram(const std::string& exe, const std::string& args) {
  return run_program_internal::RunShell(exe + " " + args);
}

// How RunProgramWithStdin feeds the program's standard input.
enum class StdinFrom {
  kPipe,  // `cat FILE | exe ...`: a pipe, which cannot be mapped or seeked.
  kFile,  // `exe ... < FILE`: a regular file.
};

// Runs `exe args` with `input` as its standard input (written to a uniquely named file
// first, removed afterwards). Only the program's stderr is captured in `err` (not cat's).
inline ProgramRun RunProgramWithStdin(const std::string& exe, const std::string& args,
                                      const std::string& input, StdinFrom from = StdinFrom::kPipe) {
  const std::string in_path = run_program_internal::UniqueName("in");
  {
    std::ofstream in(in_path, std::ios::binary);
    in << input;
  }
  const std::string cmd = from == StdinFrom::kPipe ? "cat " + in_path + " | " + exe + " " + args
                                                   : exe + " " + args + " <" + in_path;
  ProgramRun r = run_program_internal::RunShell(cmd);
  std::remove(in_path.c_str());
  return r;
}

}  // namespace metro::testing
