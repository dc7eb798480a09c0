// Physical units, parsed and converted by UDUNITS-2 (Unidata; Debian libudunits2-dev) with
// its own SI database, plus metro's aliases for the IMU vocabulary (docs/budget-format.md,
// "Units"):
//
//   text            means                               UDUNITS-2 definition
//   deg             plane angle degree                  arc_degree = (pi/180) rad
//   dps             degree per second                   arc_degree/s
//   g_n, g0         standard gravity (CGPM 1901)        9.80665 m/s^2 (exact); mg_n = 1e-3 g_n
//   mps2            metre per second squared            m/s^2
//   LSB, lsb        a count of a sensor's ADC           1 (dimensionless, like UDUNITS "count")
//
// A bare `g` is the gram, as in UDUNITS-2 and the SI (so `mg` is the milligram of JCGM 101
// 9.3); standard gravity is written g_n or g0. The radian is the dimensionless 1 (SI Brochure
// 2019, 2.3.3): rad, deg, %, ppm and LSB are all convertible to 1, and deg -> rad is the
// factor pi/180.
//
// A conversion is value_to = factor * value_from + offset (offset non-zero only between
// offset scales such as degC and K). The unit system is loaded once, on first use, and
// shared read-only; every call into UDUNITS-2 is serialised (its parser is not reentrant), so
// these functions may be called from any thread.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "metro/core/status.hpp"

namespace metro {

struct UnitConversion {
  std::string from;     // As written ("deg").
  std::string to;       // As written ("rad").
  double factor = 1.0;  // value_to = factor * value_from + offset.
  double offset = 0.0;
  // A difference or an uncertainty converts by the factor alone.
  double ConvertValue(double value_from) const { return factor * value_from + offset; }
  double ConvertDifference(double difference_from) const { return factor * difference_from; }
  // True when factor is 1 and offset 0 (to 1e-12): the same unit under two names (rad, 1).
  bool IsIdentity() const;
};

class PhysicalUnit {
 public:
  // Parses `text` (UDUNITS-2 syntax: "m/s^2", "kg.m-3", "1/degC", "deg/s", with metro's
  // aliases above). Errors quote the text; an empty text is an error.
  static Result<PhysicalUnit> Parse(const std::string& text);
  // The dimensionless unit 1.
  static PhysicalUnit One();

  // Errors when UDUNITS-2 cannot form the unit (a power beyond its range, m^200 * m^200).
  Result<PhysicalUnit> Multiply(const PhysicalUnit& other) const;
  Result<PhysicalUnit> Divide(const PhysicalUnit& other) const;
  // unit^power, power in [-255, 255].
  Result<PhysicalUnit> Raise(int power) const;
  // The root'th root (m^2 -> m); an error when the dimensions have no such root (m -> ?).
  Result<PhysicalUnit> Root(int root) const;

  bool ConvertibleTo(const PhysicalUnit& other) const;
  // Convertible to 1 (rad, deg, %, LSB, 1/1...).
  bool IsDimensionless() const;
  // The conversion to `other`; nullopt when the dimensions differ.
  std::optional<UnitConversion> ConversionTo(const PhysicalUnit& other) const;
  // The same unit: convertible with factor 1 and offset 0 (rad and 1 are the same).
  bool SameAs(const PhysicalUnit& other) const;

  // The text it was parsed from, or UDUNITS-2's ASCII notation for a derived unit
  // ("m.s-2", "0.0174532925199433 rad").
  std::string ToString() const;
  // UDUNITS-2's definition in base units ("0.0174532925199433 rad", "9.80665 m.s-2").
  std::string Definition() const;

 private:
  struct Impl;
  explicit PhysicalUnit(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}
  std::shared_ptr<const Impl> impl_;
};

}  // namespace metro
