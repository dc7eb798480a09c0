// Exit codes shared by the metro programs (docs/architecture.md "Conventions", docs/unix.md
// "Exit codes").
#pragma once

#include "metro/core/status.hpp"

namespace metro::apps {

inline constexpr int kExitOk = 0;      // The work was done.
inline constexpr int kExitFailed = 1;  // The work failed (a fit did not converge, a write).
inline constexpr int kExitUsage = 2;   // Usage or input error.

// The exit code of a command that stops on `error`, from the kind its maker gave it
// (metro/core/status.hpp): bad input or usage (ErrorKind::kInput) exits 2; a run that failed
// (kFailed) and a write that failed after it started (kIo) exit 1. Every command maps an
// Error through this, so exit 2 always means "fix the command line or the input".
inline int ExitCodeFor(const Error& error) {
  switch (error.kind) {
    case ErrorKind::kInput:
      return kExitUsage;
    case ErrorKind::kFailed:
    case ErrorKind::kIo:
      return kExitFailed;
  }
  return kExitFailed;
}

}  // namespace metro::apps
