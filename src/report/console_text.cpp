#include "metro/report/console_text.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>

#include "metro/core/terminal_text.hpp"

namespace metro {
namespace {

// The message with every number replaced by '#': "n_eff = 351.5 < n/2 = 2323.5" and
// "n_eff = 278.6 < n/2 = 2329.5" are of one kind.
std::string KindOf(const std::string& message) {
  std::string kind;
  kind.reserve(message.size());
  size_t i = 0;
  while (i < message.size()) {
    const unsigned char c = static_cast<unsigned char>(message[i]);
    // A number starts at a digit, or a sign or point before one, that does not continue a
    // word: the digit of "gx2" is part of a name.
    const unsigned char prev = i > 0 ? static_cast<unsigned char>(message[i - 1]) : ' ';
    const bool in_word = std::isalpha(prev) || prev == '_';
    const bool starts_number = (std::isdigit(c) && !in_word) ||
                               ((c == '-' || c == '.') && i + 1 < message.size() &&
                                std::isdigit(static_cast<unsigned char>(message[i + 1])) &&
                                !in_word && !std::isdigit(prev));
    if (!starts_number) {
      kind += message[i++];
      continue;
    }
    ++i;
    while (i < message.size()) {
      const unsigned char d = static_cast<unsigned char>(message[i]);
      const bool exponent = (d == 'e' || d == 'E') && i + 1 < message.size() &&
                            (std::isdigit(static_cast<unsigned char>(message[i + 1])) ||
                             message[i + 1] == '-' || message[i + 1] == '+');
      if (std::isdigit(d) || d == '.' || exponent) {
        i += exponent && !std::isdigit(static_cast<unsigned char>(message[i + 1])) ? 2 : 1;
      } else {
        break;
      }
    }
    kind += '#';
  }
  return kind;
}

// "sensor 2 qx" -> ("sensor 2", "qx"); anything else is its own head.
std::pair<std::string, std::string> SplitSubject(const std::string& subject) {
  if (subject.rfind("sensor ", 0) == 0) {
    const size_t space = subject.find(' ', 7);
    if (space != std::string::npos) return {subject.substr(0, space), subject.substr(space + 1)};
  }
  return {subject, ""};
}

}  // namespace

std::string GroupedWarnings(const std::vector<WarningLine>& warnings, const std::string& indent) {
  std::vector<std::string> order;
  std::map<std::string, std::vector<const WarningLine*>> groups;
  for (const WarningLine& w : warnings) {
    const std::string kind = KindOf(w.message);
    auto [it, inserted] = groups.try_emplace(kind);
    if (inserted) order.push_back(kind);
    it->second.push_back(&w);
  }
  std::string out;
  for (const std::string& kind : order) {
    const std::vector<const WarningLine*>& g = groups[kind];
    const WarningLine& first = *g.front();
    // One warning, one line: its subject and text quote data (names, file names).
    const std::string message = EscapeControlChars(first.message);
    out += first.subject.empty()
               ? fmt::format("{}{}\n", indent, message)
               : fmt::format("{}{}: {}\n", indent, EscapeControlChars(first.subject), message);
    if (g.size() == 1) continue;
    // The others, by their head ("sensor 2"), in order: "sensor 2 qx, qy; sensor 3 qw".
    std::string names, head;
    for (size_t k = 1; k < g.size(); ++k) {
      const auto [h, rest] = SplitSubject(g[k]->subject);
      if (k == 1 || h != head) {
        if (k > 1) names += "; ";
        names += rest.empty() ? h : h + " " + rest;
        head = h;
      } else {
        names += ", " + (rest.empty() ? h : rest);
      }
    }
    out += fmt::format("{}  and {} more like it: {}\n", indent, g.size() - 1,
                       EscapeControlChars(names));
  }
  return out;
}

RoundedResult RoundForTable(double value, double u, int significant) {
  RoundedResult r = RoundForStatement(value, u, significant);
  if (!std::isfinite(u) || u <= 0.0) return r;
  // Decimals RoundForStatement kept: the last digit's place is 10^-decimals.
  const size_t point = r.uncertainty.find('.');
  const int decimals =
      point == std::string::npos ? 0 : static_cast<int>(r.uncertainty.size() - point - 1);
  if (decimals <= 6) return r;
  auto exponent_form = [&](const std::string& fixed) -> std::string {
    const double rounded = std::strtod(fixed.c_str(), nullptr);
    if (rounded == 0.0) return fixed;
    const int e = static_cast<int>(std::floor(std::log10(std::fabs(rounded))));
    if (e >= -3) return fixed;  // |x| >= 0.001 reads well as is.
    return fmt::format("{:.{}e}", rounded, std::max(0, decimals + e));
  };
  return {exponent_form(r.value), exponent_form(r.uncertainty)};
}

std::string ConsoleNumber(double x) {
  const double a = std::fabs(x);
  if (a != 0.0 && std::isfinite(a) && (a < 1e-3 || a >= 1e6)) return fmt::format("{:.2e}", x);
  return fmt::format("{:.3g}", x);
}

}  // namespace metro
