// The characterize subcommands' output rules are the ones both programs share: outputs
// checked before any work (CheckOutputs), written atomically and together (WriteOutputs),
// errors and notes printed safely (PrintError, Note); `-` is standard output. See
// unix_cli.hpp.
#pragma once

#include "unix_cli.hpp"
