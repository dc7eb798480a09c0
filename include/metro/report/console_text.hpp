// Console text shared by the programs' tables (issue #25 point 6): warnings grouped by kind,
// and a value with its uncertainty rounded for a table column.
#pragma once

#include <string>
#include <vector>

#include "metro/core/rounding.hpp"

namespace metro {

// One warning as a report holds it: what it is about ("sensor 2 qz", "input") and the text.
struct WarningLine {
  std::string subject;
  std::string message;
};

// The warnings as console lines, near-identical ones grouped: two messages are alike when
// they differ only in their numbers. The first of each kind is printed whole ("  subject:
// message"), the rest counted and named below it ("    and 6 more like it: sensor 2 qx, qy;
// sensor 3 qw"); kinds keep the order of their first line. Each line starts with `indent`.
std::string GroupedWarnings(const std::vector<WarningLine>& warnings,
                            const std::string& indent = "  ");

// RoundForStatement (JCGM 100 7.2.6) for a table column: where fixed notation would need
// more than six decimals, the number is written in exponent notation with the same last
// digit (u 3.7e-08 rather than 0.000000037; a mean of -0.000018 next to it, -1.8e-05).
RoundedResult RoundForTable(double value, double u, int significant = 2);

// Three significant digits for a console table cell, in exponent notation below 0.001
// (1.22e-04, not 0.000122) and from 1e6 on. (The HTML pages' ShortNumber(x, digits) in
// src/report/html_common.hpp keeps %g, whose fixed notation reads well in a page's columns.)
std::string ConsoleNumber(double x);

}  // namespace metro
