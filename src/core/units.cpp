#include "metro/core/units.hpp"

#include <udunits2.h>

#include <cmath>
#include <mutex>
#include <utility>

#include "metro/core/check.hpp"

namespace metro {
namespace {

// UDUNITS-2's parser (a yacc grammar) and its status variable are global: one lock for
// every call.
std::mutex& UdunitsMutex() {
  static std::mutex mutex;
  return mutex;
}

ut_unit* ParseLocked(ut_system* system, const std::string& text) {
  return ut_parse(system, text.c_str(), UT_UTF8);
}

// The unit system with metro's aliases; loaded once. Must be called with the lock held.
ut_system* SystemLocked() {
  static ut_system* const system = [] {
    // The bundled XML database redefines a few names, and a failed parse or root prints a
    // line: metro reports every failure itself, so UDUNITS-2 stays quiet.
    ut_set_error_message_handler(ut_ignore);
    ut_system* s = ut_read_xml(nullptr);
    METRO_CHECK(s != nullptr);  // libudunits2-dev installs the database with the library.
    ut_unit* degree = ParseLocked(s, "arc_degree");
    ut_unit* metre_per_s2 = ParseLocked(s, "m/s^2");
    ut_unit* per_second = ParseLocked(s, "1/s");
    METRO_CHECK(degree != nullptr && metre_per_s2 != nullptr && per_second != nullptr);
    ut_unit* standard_gravity = ut_scale(9.80665, metre_per_s2);  // CGPM 1901, exact.
    ut_unit* degree_per_second = ut_multiply(degree, per_second);
    ut_unit* one = ut_get_dimensionless_unit_one(s);
    METRO_CHECK(ut_map_symbol_to_unit("deg", UT_ASCII, degree) == UT_SUCCESS);
    METRO_CHECK(ut_map_symbol_to_unit("dps", UT_ASCII, degree_per_second) == UT_SUCCESS);
    METRO_CHECK(ut_map_name_to_unit("g_n", UT_ASCII, standard_gravity) == UT_SUCCESS);
    METRO_CHECK(ut_map_symbol_to_unit("LSB", UT_ASCII, one) == UT_SUCCESS);
    METRO_CHECK(ut_map_symbol_to_unit("lsb", UT_ASCII, one) == UT_SUCCESS);
    for (ut_unit* u :
         {degree, metre_per_s2, per_second, standard_gravity, degree_per_second, one}) {
      ut_free(u);
    }
    return s;
  }();
  return system;
}

bool IsNameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

// Aliases UDUNITS-2 cannot hold as symbols: its grammar reads a digit after a name as an
// exponent ("g0" would be g^0 = 1, "mps2" mps^2).
std::string ExpandAliases(const std::string& text) {
  std::string out;
  size_t i = 0;
  while (i < text.size()) {
    if (!IsNameChar(text[i])) {
      out += text[i++];
      continue;
    }
    size_t j = i;
    while (j < text.size() && IsNameChar(text[j])) ++j;
    const std::string word = text.substr(i, j - i);
    if (word == "g0") {
      out += "g_n";
    } else if (word == "mg0") {
      out += "mg_n";
    } else if (word == "mps2") {
      out += "(m/s^2)";
    } else {
      out += word;
    }
    i = j;
  }
  return out;
}

std::string Trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = text.find_last_not_of(" \t\r\n");
  return text.substr(first, last - first + 1);
}

std::string FormatLocked(const ut_unit* unit, unsigned opts) {
  char buffer[256];
  const int n = ut_format(unit, buffer, sizeof buffer, opts | UT_ASCII);
  if (n < 0 || static_cast<size_t>(n) >= sizeof buffer) return "?";
  return std::string(buffer, static_cast<size_t>(n));
}

}  // namespace

struct PhysicalUnit::Impl {
  ut_unit* unit = nullptr;
  std::string text;  // As parsed; empty for a derived unit.
  Impl(ut_unit* u, std::string t) : unit(u), text(std::move(t)) {}
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl() {
    std::lock_guard<std::mutex> lock(UdunitsMutex());
    ut_free(unit);
  }
};

bool UnitConversion::IsIdentity() const {
  return std::fabs(factor - 1.0) <= 1e-12 && std::fabs(offset) <= 1e-12;
}

Result<PhysicalUnit> PhysicalUnit::Parse(const std::string& text) {
  const std::string trimmed = Trim(text);
  if (trimmed.empty()) return MakeError("empty unit (write \"1\" for a dimensionless quantity)");
  ut_unit* unit = nullptr;
  {
    std::lock_guard<std::mutex> lock(UdunitsMutex());
    unit = ParseLocked(SystemLocked(), ExpandAliases(trimmed));
  }
  if (unit == nullptr) {
    return MakeError("unknown unit '" + text +
                     "' (UDUNITS-2 syntax, e.g. m/s^2, kg.m-3, 1/degC; metro adds deg, dps, g_n "
                     "or g0 for standard gravity, mps2, LSB; g is the gram)");
  }
  return PhysicalUnit(std::make_shared<const Impl>(unit, trimmed));
}

PhysicalUnit PhysicalUnit::One() {
  std::lock_guard<std::mutex> lock(UdunitsMutex());
  return PhysicalUnit(std::make_shared<const Impl>(ut_get_dimensionless_unit_one(SystemLocked()),
                                                   std::string("1")));
}

Result<PhysicalUnit> PhysicalUnit::Multiply(const PhysicalUnit& other) const {
  std::lock_guard<std::mutex> lock(UdunitsMutex());
  ut_unit* product = ut_multiply(impl_->unit, other.impl_->unit);
  if (product == nullptr) {
    return MakeError("cannot multiply " + FormatLocked(impl_->unit, 0) + " by " +
                     FormatLocked(other.impl_->unit, 0));
  }
  return PhysicalUnit(std::make_shared<const Impl>(product, std::string()));
}

Result<PhysicalUnit> PhysicalUnit::Divide(const PhysicalUnit& other) const {
  std::lock_guard<std::mutex> lock(UdunitsMutex());
  ut_unit* quotient = ut_divide(impl_->unit, other.impl_->unit);
  if (quotient == nullptr) {
    return MakeError("cannot divide " + FormatLocked(impl_->unit, 0) + " by " +
                     FormatLocked(other.impl_->unit, 0));
  }
  return PhysicalUnit(std::make_shared<const Impl>(quotient, std::string()));
}

Result<PhysicalUnit> PhysicalUnit::Raise(int power) const {
  if (power < -255 || power > 255) {
    return MakeError("unit power " + std::to_string(power) + " out of range [-255, 255]");
  }
  std::lock_guard<std::mutex> lock(UdunitsMutex());
  ut_unit* raised = ut_raise(impl_->unit, power);
  if (raised == nullptr)
    return MakeError("cannot raise unit to the power " + std::to_string(power));
  return PhysicalUnit(std::make_shared<const Impl>(raised, std::string()));
}

Result<PhysicalUnit> PhysicalUnit::Root(int root) const {
  if (root < 1 || root > 255)
    return MakeError("unit root " + std::to_string(root) + " out of range");
  std::lock_guard<std::mutex> lock(UdunitsMutex());
  ut_unit* rooted = ut_root(impl_->unit, root);
  if (rooted == nullptr) {
    return MakeError("the unit " + FormatLocked(impl_->unit, 0) + " has no " +
                     std::to_string(root) +
                     (root == 2   ? "nd"
                      : root == 3 ? "rd"
                                  : "th") +
                     " root");
  }
  return PhysicalUnit(std::make_shared<const Impl>(rooted, std::string()));
}

bool PhysicalUnit::ConvertibleTo(const PhysicalUnit& other) const {
  std::lock_guard<std::mutex> lock(UdunitsMutex());
  return ut_are_convertible(impl_->unit, other.impl_->unit) != 0;
}

bool PhysicalUnit::IsDimensionless() const {
  std::lock_guard<std::mutex> lock(UdunitsMutex());
  return ut_are_convertible(impl_->unit, ut_get_dimensionless_unit_one(SystemLocked())) != 0;
}

std::optional<UnitConversion> PhysicalUnit::ConversionTo(const PhysicalUnit& other) const {
  UnitConversion c;
  {
    std::lock_guard<std::mutex> lock(UdunitsMutex());
    if (ut_are_convertible(impl_->unit, other.impl_->unit) == 0) return std::nullopt;
    cv_converter* converter = ut_get_converter(impl_->unit, other.impl_->unit);
    METRO_CHECK(converter != nullptr);
    c.offset = cv_convert_double(converter, 0.0);
    c.factor = cv_convert_double(converter, 1.0) - c.offset;
    cv_free(converter);
  }
  c.from = ToString();
  c.to = other.ToString();
  return c;
}

bool PhysicalUnit::SameAs(const PhysicalUnit& other) const {
  const std::optional<UnitConversion> c = ConversionTo(other);
  return c && c->IsIdentity();
}

std::string PhysicalUnit::ToString() const {
  if (!impl_->text.empty()) return impl_->text;
  std::lock_guard<std::mutex> lock(UdunitsMutex());
  return FormatLocked(impl_->unit, 0);
}

std::string PhysicalUnit::Definition() const {
  std::lock_guard<std::mutex> lock(UdunitsMutex());
  return FormatLocked(impl_->unit, UT_DEFINITION);
}

}  // namespace metro
