// Exit codes shared by the metro programs (STYLE.md rule 16).
#pragma once

namespace metro::apps {

inline constexpr int kExitOk = 0;      // The work was done.
inline constexpr int kExitFailed = 1;  // The work failed (a fit did not converge, a write).
inline constexpr int kExitUsage = 2;   // Usage or input error.

}  // namespace metro::apps
