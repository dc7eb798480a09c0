// ParseInput reads one budget input in these stages, in this order:
//
//   keys          Fields::OnlyKeys, unit, sensitivity    the keys an input may have
//   Type A        ReadTypeA                             'type_a' (values, summary, session)
//   distribution  DistributionFromName, ReadDof         the distribution; dof or reliability
//   estimate      ReadNormal, ReadBounded,              value and u by distribution, each
//                 ReadStudentT, Forbid                  refusing the keys that do not apply
#include "metro/uncertainty/budget.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <tuple>

#include "core/json_reader.hpp"
#include "core/json_text.hpp"
#include "metro/core/file.hpp"
#include "metro/core/terminal_text.hpp"
#include "metro/stats/type_a.hpp"
#include "uncertainty/model.hpp"
#include "uncertainty/model_quote.hpp"
#include "uncertainty/model_units.hpp"

namespace metro {
namespace {

using nlohmann::json;

// Reads a field of an object; reports type errors with the owner's name.
class Fields {
 public:
  Fields(const json& object, std::string owner, std::string file)
      : object_(object), owner_(std::move(owner)), file_(std::move(file)) {}

  bool Has(const char* key) const { return object_.contains(key); }

  Error Fail(const std::string& message) const {
    return MakeError(file_, 0, owner_ + ": " + message);
  }

  // Unknown keys are errors: a misspelt "halfwidth" must not silently become a default.
  Status OnlyKeys(const std::set<std::string>& allowed) const {
    for (const auto& [key, value] : object_.items()) {
      (void)value;
      if (allowed.count(key) == 0) return Fail("unknown key '" + key + "'");
    }
    return Status();
  }

  Result<std::optional<double>> Number(const char* key) const {
    if (!Has(key)) return std::optional<double>();
    const json& v = object_.at(key);
    if (!v.is_number()) return Fail("'" + std::string(key) + "' must be a number");
    const double x = v.get<double>();
    if (!std::isfinite(x)) return Fail("'" + std::string(key) + "' must be finite");
    return std::optional<double>(x);
  }

  Result<double> RequiredNumber(const char* key, const std::string& what) const {
    auto x = Number(key);
    if (!x.ok()) return x.error();
    if (!x.value()) return Fail("missing '" + std::string(key) + "' (" + what + ")");
    return *x.value();
  }

  Result<std::string> String(const char* key, bool required) const {
    if (!Has(key)) {
      if (required) return Fail("missing '" + std::string(key) + "'");
      return std::string();
    }
    const json& v = object_.at(key);
    if (!v.is_string()) return Fail("'" + std::string(key) + "' must be a string");
    return v.get<std::string>();
  }

  Result<std::optional<bool>> Bool(const char* key) const {
    if (!Has(key)) return std::optional<bool>();
    const json& v = object_.at(key);
    if (!v.is_boolean()) return Fail("'" + std::string(key) + "' must be true or false");
    return std::optional<bool>(v.get<bool>());
  }

  Result<std::optional<int64_t>> Integer(const char* key) const {
    auto x = Number(key);
    if (!x.ok()) return x.error();
    if (!x.value()) return std::optional<int64_t>();
    const double v = *x.value();
    if (v != std::floor(v) || std::fabs(v) > 9.0e15) {
      return Fail("'" + std::string(key) + "' must be an integer");
    }
    return std::optional<int64_t>(static_cast<int64_t>(v));
  }

  const json& object() const { return object_; }
  const std::string& owner() const { return owner_; }

 private:
  const json& object_;
  std::string owner_;
  std::string file_;
};

#define METRO_ASSIGN_OR_RETURN(lhs, expr)              \
  auto lhs##_result = (expr);                          \
  if (!lhs##_result.ok()) return lhs##_result.error(); \
  auto lhs = std::move(lhs##_result).value()

std::string DirectoryOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return "";
  return path.substr(0, slash + 1);
}

Result<std::optional<Distribution>> DistributionFromName(const Fields& f, const std::string& s) {
  static const std::map<std::string, Distribution> kNames = {
      {"normal", Distribution::kNormal},
      {"gaussian", Distribution::kNormal},
      {"rectangular", Distribution::kRectangular},
      {"uniform", Distribution::kRectangular},
      {"triangular", Distribution::kTriangular},
      {"arcsine", Distribution::kArcsine},
      {"u-shaped", Distribution::kArcsine},
      {"trapezoidal", Distribution::kTrapezoidal},
      {"ctrap", Distribution::kCurvilinearTrapezoid},
      {"t", Distribution::kStudentT},
  };
  const auto it = kNames.find(s);
  if (it == kNames.end()) {
    return f.Fail("unknown distribution '" + s +
                  "' (expected normal, rectangular, triangular, arcsine, trapezoidal, ctrap, t "
                  "or a \"type_a\" object)");
  }
  return std::optional<Distribution>(it->second);
}

// value + half_width, or lower + upper (value = midpoint).
Status ReadLimits(const Fields& f, BudgetInput* in) {
  METRO_ASSIGN_OR_RETURN(value, f.Number("value"));
  METRO_ASSIGN_OR_RETURN(half_width, f.Number("half_width"));
  METRO_ASSIGN_OR_RETURN(lower, f.Number("lower"));
  METRO_ASSIGN_OR_RETURN(upper, f.Number("upper"));
  const std::string name = DistributionName(in->distribution);
  if (lower || upper) {
    if (!lower || !upper) return f.Fail(name + " needs both 'lower' and 'upper'");
    if (half_width || value) {
      return f.Fail(name + ": give either 'value' and 'half_width' or 'lower' and 'upper'");
    }
    if (*upper < *lower) return f.Fail("'upper' must not be below 'lower'");
    in->value = 0.5 * (*lower + *upper);
    in->half_width = 0.5 * (*upper - *lower);
    return Status();
  }
  if (!half_width) return f.Fail(name + " needs 'half_width' (or 'lower' and 'upper')");
  if (!value) return f.Fail("missing 'value' (the centre of the " + name + " distribution)");
  if (*half_width < 0.0) return f.Fail("'half_width' must be >= 0");
  in->value = *value;
  in->half_width = *half_width;
  return Status();
}

// A session quantity carries its own unit (the column's suffix, docs/formats.md): an input
// without "unit" takes it; an input in another unit of the same dimension gets the mean and u
// converted (value_to = factor * value + offset, u_to = |factor| * u); other units are refused.
Status ConvertSessionUnit(const Fields& f, const std::string& quantity,
                          const std::string& session_unit, BudgetInput* in) {
  if (session_unit.empty()) return Status();
  if (in->unit.empty()) {
    in->unit = session_unit;
    return Status();
  }
  auto from = PhysicalUnit::Parse(session_unit);
  if (!from.ok()) return f.Fail("session quantity '" + quantity + "': " + from.error().message);
  auto to = PhysicalUnit::Parse(in->unit);
  if (!to.ok()) return f.Fail(to.error().message);
  const std::optional<UnitConversion> c = from.value().ConversionTo(to.value());
  if (!c) {
    std::string hint;
    if (to.value().ConvertibleTo(PhysicalUnit::Parse("kg").value()) &&
        from.value().ConvertibleTo(PhysicalUnit::Parse("m/s^2").value())) {
      hint = " (g is the gram; standard gravity is g_n or g0)";
    }
    return f.Fail("session quantity '" + quantity + "' is in " + session_unit +
                  ", which cannot be converted to the input's unit '" + in->unit + "'" + hint);
  }
  if (c->IsIdentity()) return Status();
  in->value_before_conversion = in->value;
  in->u_before_conversion = in->u;
  in->value = c->ConvertValue(in->value);
  in->u = std::fabs(c->ConvertDifference(in->u));
  in->unit_conversion = c;
  in->note += "; converted from " + session_unit + " to " + in->unit;
  return Status();
}

Status ReadTypeA(const Fields& f, const std::string& budget_path,
                 const SessionQuantityResolver& resolver, BudgetInput* in) {
  const json& t = f.object().at("type_a");
  if (!t.is_object()) return f.Fail("'type_a' must be an object");
  for (const char* key :
       {"value", "u", "dof", "reliability", "distribution", "expanded", "half_width", "scale"}) {
    if (f.Has(key)) {
      return f.Fail("'" + std::string(key) + "' cannot be combined with 'type_a'");
    }
  }
  Fields a(t, f.owner() + " type_a", "");
  in->distribution = Distribution::kTypeA;
  if (a.Has("values")) {
    if (auto s = a.OnlyKeys({"values", "resolution", "truncated"}); !s.ok()) {
      return f.Fail(s.error().message);
    }
    METRO_ASSIGN_OR_RETURN(resolution, a.Number("resolution"));
    METRO_ASSIGN_OR_RETURN(truncated, a.Bool("truncated"));
    if (resolution && !(*resolution > 0.0 && std::isfinite(*resolution))) {
      return f.Fail("'type_a.resolution' must be > 0 (the readings' quantization step), got " +
                    fmt::format("{}", *resolution));
    }
    if (truncated && *truncated && !resolution) {
      return f.Fail("'type_a.truncated' needs the readings' 'resolution'");
    }
    const json& values = t.at("values");
    if (!values.is_array()) return f.Fail("'type_a.values' must be an array of numbers");
    std::vector<double> q;
    for (const auto& v : values) {
      if (!v.is_number()) return f.Fail("'type_a.values' must be an array of numbers");
      q.push_back(v.get<double>());
    }
    if (q.size() < 2) return f.Fail("'type_a.values' needs at least 2 observations");
    // JCGM 100 4.2.1 - 4.2.3: q_bar, s^2(q_k) with n - 1, s(q_bar) = s/sqrt(n).
    double mean = 0.0;
    for (double x : q) mean += x;
    mean /= static_cast<double>(q.size());
    double ss = 0.0;
    for (double x : q) ss += (x - mean) * (x - mean);
    const double n = static_cast<double>(q.size());
    in->value = mean;
    in->u = std::sqrt(ss / (n - 1.0) / n);
    in->n = static_cast<int64_t>(q.size());
    in->dof = n - 1.0;
    in->note = "Type A from " + std::to_string(q.size()) + " observations";
    if (resolution) {
      // Digitized readings: Willink's rules (Metrologia 44 (2007) 73; stats/type_a.hpp), the
      // observations taken as independent like the lines above.
      TypeAOptions options;
      options.autocorrelation = false;
      options.quantization_step = *resolution;
      options.truncated = truncated.value_or(false);
      Result<TypeAResult> r = EvaluateTypeA(q.data(), q.size(), options);
      if (!r.ok()) return f.Fail("'type_a.values': " + r.error().message);
      in->value = r.value().mean;
      in->u = r.value().u_mean;
      in->note += r.value().u_mean_method == kUMeanDigitized
                      ? fmt::format(", digitized (resolution {}{}): Willink's rules", *resolution,
                                    options.truncated ? ", truncated" : "")
                      : fmt::format(", resolution {}{}: spread over more than one step",
                                    *resolution, options.truncated ? ", truncated" : "");
    } else if (ss == 0.0) {
      // s = 0 would state u = 0 for the mean of readings that only agree to their resolution
      // (issue #36).
      return f.Fail(
          "'type_a.values' are all equal (s = 0): a Type A u of 0 is not an uncertainty; give "
          "the readings' \"resolution\" (their quantization step: Willink's rules for "
          "digitized readings, docs/budget-format.md) or a Type B input");
    }
  } else if (a.Has("mean") || a.Has("std") || a.Has("n")) {
    if (auto s = a.OnlyKeys({"mean", "std", "n"}); !s.ok()) return f.Fail(s.error().message);
    METRO_ASSIGN_OR_RETURN(mean, a.RequiredNumber("mean", "mean of the observations"));
    METRO_ASSIGN_OR_RETURN(s, a.RequiredNumber("std", "standard deviation of one observation"));
    METRO_ASSIGN_OR_RETURN(n, a.Integer("n"));
    if (!n) return f.Fail("missing 'type_a.n' (number of observations)");
    if (*n < 2) return f.Fail("'type_a.n' must be at least 2");
    if (s < 0.0) return f.Fail("'type_a.std' must be >= 0, got " + std::to_string(s));
    in->value = mean;
    in->u = s / std::sqrt(static_cast<double>(*n));
    in->n = *n;
    in->dof = static_cast<double>(*n - 1);
    in->note = "Type A from mean, std and n = " + std::to_string(*n);
  } else if (a.Has("quantity") || a.Has("session") || a.Has("sensor")) {
    if (auto s = a.OnlyKeys({"session", "sensor", "quantity"}); !s.ok()) {
      return f.Fail(s.error().message);
    }
    SessionQuantityRef ref;
    METRO_ASSIGN_OR_RETURN(session, a.String("session", false));
    METRO_ASSIGN_OR_RETURN(quantity, a.String("quantity", true));
    METRO_ASSIGN_OR_RETURN(sensor, a.Integer("sensor"));
    if (!session.empty() && session[0] != '/') session = DirectoryOf(budget_path) + session;
    ref.session = session;
    ref.quantity = quantity;
    ref.sensor = sensor ? static_cast<int>(*sensor) : 1;
    if (!resolver) {
      return f.Fail("refers to session quantity '" + quantity +
                    "' but no session resolver was given (use `characterize SESSION --type-a "
                    "--budget`)");
    }
    Result<TypeASummary> summary = resolver(ref);
    if (!summary.ok()) return f.Fail(summary.error().ToString());
    const TypeASummary& s = summary.value();
    if (!std::isfinite(s.mean) || !(s.u >= 0.0) || !std::isfinite(s.u) || !(s.dof > 0.0)) {
      return f.Fail("the session summary of '" + quantity + "' is not usable (mean " +
                    std::to_string(s.mean) + ", u " + std::to_string(s.u) + ", dof " +
                    std::to_string(s.dof) + ")");
    }
    in->value = s.mean;
    in->u = s.u;
    in->dof = s.dof;
    in->n = s.n;
    in->note = s.note.empty() ? "Type A from session quantity " + quantity : s.note;
    in->session = ref;
    if (auto c = ConvertSessionUnit(f, quantity, s.unit, in); !c.ok()) return c;
  } else {
    return f.Fail("'type_a' needs 'values', or 'mean', 'std' and 'n', or a session 'quantity'");
  }
  in->scale = in->u;
  return Status();
}

// ---- ParseInput's stages ------------------------------------------------------------------

// 'dof' or 'reliability' (JCGM 100 G.4.2) into in->dof; the 'dof' given, if any.
Result<std::optional<double>> ReadDof(const Fields& f, BudgetInput* in) {
  METRO_ASSIGN_OR_RETURN(dof, f.Number("dof"));
  METRO_ASSIGN_OR_RETURN(reliability, f.Number("reliability"));
  if (dof && reliability) return f.Fail("give 'dof' or 'reliability', not both");
  if (dof && !(*dof > 0.0)) return f.Fail("'dof' must be > 0, got " + std::to_string(*dof));
  if (reliability) {
    if (!(*reliability > 0.0)) return f.Fail("'reliability' must be > 0");
    in->dof = 1.0 / (2.0 * *reliability * *reliability);  // JCGM 100 G.4.2
  }
  if (dof) in->dof = *dof;
  return dof;
}

// An error naming the first of `keys` given for a distribution it does not apply to.
Status Forbid(const Fields& f, const std::string& distribution_name,
              std::initializer_list<const char*> keys) {
  for (const char* key : keys) {
    if (f.Has(key)) {
      return f.Fail("'" + std::string(key) + "' does not apply to a " + distribution_name +
                    " distribution");
    }
  }
  return Status();
}

// A normal input: the estimate and u, or U with k or coverage (JCGM 100 4.3.3, 4.3.4, G.3).
Status ReadNormal(const Fields& f, const std::string& distribution_name, BudgetInput* in) {
  if (auto s = Forbid(f, distribution_name, {"half_width", "lower", "upper", "beta", "d", "scale"});
      !s.ok()) {
    return s;
  }
  METRO_ASSIGN_OR_RETURN(value, f.RequiredNumber("value", "the estimate"));
  METRO_ASSIGN_OR_RETURN(u, f.Number("u"));
  METRO_ASSIGN_OR_RETURN(expanded, f.Number("expanded"));
  METRO_ASSIGN_OR_RETURN(k, f.Number("k"));
  METRO_ASSIGN_OR_RETURN(coverage, f.Number("coverage"));
  in->value = value;
  if (u && expanded) return f.Fail("give 'u' or 'expanded', not both");
  if (u) {
    if (k || coverage) return f.Fail("'k' and 'coverage' go with 'expanded', not 'u'");
    if (*u < 0.0) return f.Fail("u must be >= 0, got " + std::to_string(*u));
    in->u = *u;
  } else if (expanded) {
    if (*expanded < 0.0) {
      return f.Fail("'expanded' must be >= 0, got " + std::to_string(*expanded));
    }
    if (k && coverage) return f.Fail("give 'k' or 'coverage' with 'expanded', not both");
    if (k) {
      if (!(*k > 0.0)) return f.Fail("'k' must be > 0");
      in->u = *expanded / *k;  // JCGM 100 4.3.3
      in->note = "u = U/k";
    } else if (coverage) {
      if (!(*coverage > 0.0 && *coverage < 1.0)) {
        return f.Fail("'coverage' must be in (0, 1), got " + std::to_string(*coverage));
      }
      // JCGM 100 4.3.4; with stated dof the quantile is t_p(nu) (G.3).
      const double tail = 0.5 * (1.0 + *coverage);
      double factor = 0.0;
      if (std::isfinite(in->dof)) {
        factor = boost::math::quantile(boost::math::students_t(in->dof), tail);
      } else {
        factor = boost::math::quantile(boost::math::normal(), tail);
      }
      in->u = *expanded / factor;
      in->note = "u = U/" + std::string(std::isfinite(in->dof) ? "t_p(nu)" : "z_p");
    } else {
      return f.Fail("'expanded' needs 'k' or 'coverage'");
    }
  } else {
    return f.Fail(
        "missing 'u' (or 'expanded' with 'k' or 'coverage'); use \"u\": 0 for an exact "
        "constant");
  }
  return Status();
}

// A bounded input (rectangular, triangular, arcsine, trapezoidal, curvilinear trapezoid):
// its limits and u from its half-width.
Status ReadBounded(const Fields& f, const std::string& distribution_name, BudgetInput* in) {
  const auto forbid = [&](std::initializer_list<const char*> keys) {
    return Forbid(f, distribution_name, keys);
  };
  if (auto s = forbid({"u", "expanded", "k", "coverage", "scale"}); !s.ok()) return s;
  if (in->distribution != Distribution::kTrapezoidal) {
    if (auto s = forbid({"beta"}); !s.ok()) return s;
  }
  if (in->distribution != Distribution::kCurvilinearTrapezoid) {
    if (auto s = forbid({"d"}); !s.ok()) return s;
  }
  if (auto s = ReadLimits(f, in); !s.ok()) return s;
  const double a = in->half_width;
  if (in->distribution == Distribution::kRectangular) {
    in->u = a / std::sqrt(3.0);  // JCGM 100 4.3.7
  } else if (in->distribution == Distribution::kTriangular) {
    in->u = a / std::sqrt(6.0);  // JCGM 100 4.3.9
  } else if (in->distribution == Distribution::kArcsine) {
    in->u = a / std::sqrt(2.0);  // JCGM 101 6.4.6.3
  } else if (in->distribution == Distribution::kTrapezoidal) {
    METRO_ASSIGN_OR_RETURN(beta, f.RequiredNumber("beta", "top/bottom half-width ratio"));
    if (!(beta >= 0.0 && beta <= 1.0)) {
      return f.Fail("'beta' must be in [0, 1], got " + std::to_string(beta));
    }
    in->beta = beta;
    in->u = a * std::sqrt((1.0 + beta * beta) / 6.0);  // JCGM 101 6.4.4.3
  } else {
    METRO_ASSIGN_OR_RETURN(d, f.RequiredNumber("d", "half-width of the uncertain limits"));
    if (!(d >= 0.0 && d <= a)) {
      return f.Fail("'d' must be in [0, half_width], got " + std::to_string(d));
    }
    in->d = d;
    in->u = std::sqrt(a * a / 3.0 + d * d / 9.0);  // JCGM 101 6.4.3.3
  }
  return Status();
}

// A t-distributed input t_nu(x, s^2): location, scale and the dof it needs.
Status ReadStudentT(const Fields& f, const std::string& distribution_name,
                    const std::optional<double>& dof, BudgetInput* in) {
  if (auto s =
          Forbid(f, distribution_name,
                 {"u", "expanded", "k", "coverage", "half_width", "lower", "upper", "beta", "d"});
      !s.ok()) {
    return s;
  }
  METRO_ASSIGN_OR_RETURN(value, f.RequiredNumber("value", "the location"));
  METRO_ASSIGN_OR_RETURN(scale, f.RequiredNumber("scale", "the scale s of t_nu(x, s^2)"));
  if (!dof) return f.Fail("missing 'dof' (degrees of freedom of the t distribution)");
  if (scale < 0.0) return f.Fail("'scale' must be >= 0, got " + std::to_string(scale));
  in->value = value;
  in->scale = scale;
  in->u = scale;  // As for Type A (JCGM 100 4.2.3; JCGM 101 6.4.9.2).
  return Status();
}

Result<BudgetInput> ParseInput(const json& object, size_t index, const std::string& path,
                               const SessionQuantityResolver& resolver) {
  if (!object.is_object()) {
    return MakeError(path, 0, "inputs[" + std::to_string(index) + "] must be an object");
  }
  BudgetInput in;
  if (!object.contains("name") || !object.at("name").is_string() ||
      object.at("name").get<std::string>().empty()) {
    return MakeError(path, 0, "inputs[" + std::to_string(index) + "]: missing 'name'");
  }
  in.name = object.at("name").get<std::string>();
  Fields f(object, "input '" + in.name + "'", path);
  if (auto s = f.OnlyKeys({"name",        "value",    "u",     "dof",      "distribution",
                           "half_width",  "lower",    "upper", "beta",     "d",
                           "scale",       "expanded", "k",     "coverage", "reliability",
                           "sensitivity", "type_a",   "unit",  "note",     "description"});
      !s.ok()) {
    return s.error();
  }
  METRO_ASSIGN_OR_RETURN(unit, f.String("unit", false));
  in.unit = unit;
  METRO_ASSIGN_OR_RETURN(sensitivity, f.Number("sensitivity"));
  in.sensitivity = sensitivity;

  if (f.Has("type_a")) {
    if (auto s = ReadTypeA(f, path, resolver, &in); !s.ok()) return s.error();
    return in;
  }

  METRO_ASSIGN_OR_RETURN(distribution_name, f.String("distribution", false));
  if (distribution_name.empty()) distribution_name = "normal";
  METRO_ASSIGN_OR_RETURN(distribution, DistributionFromName(f, distribution_name));
  in.distribution = *distribution;
  METRO_ASSIGN_OR_RETURN(dof, ReadDof(f, &in));
  Status read;
  switch (in.distribution) {
    case Distribution::kNormal:
      read = ReadNormal(f, distribution_name, &in);
      break;
    case Distribution::kRectangular:
    case Distribution::kTriangular:
    case Distribution::kArcsine:
    case Distribution::kTrapezoidal:
    case Distribution::kCurvilinearTrapezoid:
      read = ReadBounded(f, distribution_name, &in);
      break;
    case Distribution::kStudentT:
      read = ReadStudentT(f, distribution_name, dof, &in);
      break;
    case Distribution::kTypeA:
      METRO_CHECK(false);
  }
  if (!read.ok()) return read.error();
  if (in.distribution == Distribution::kNormal) in.scale = in.u;
  METRO_ASSIGN_OR_RETURN(note, f.String("note", false));
  if (!note.empty()) in.note = note;
  return in;
}

Result<GumOptions> ParseGumOptions(const json& object, const std::string& path, double coverage) {
  GumOptions options;
  options.coverage = coverage;
  if (object.is_null()) return options;
  if (!object.is_object()) return MakeError(path, 0, "'gum' must be an object");
  Fields f(object, "gum", path);
  if (auto s = f.OnlyKeys({"second_order", "truncate_dof", "dof_policy", "step_fraction"});
      !s.ok()) {
    return s.error();
  }
  METRO_ASSIGN_OR_RETURN(second, f.Bool("second_order"));
  METRO_ASSIGN_OR_RETURN(truncate, f.Bool("truncate_dof"));
  METRO_ASSIGN_OR_RETURN(policy, f.String("dof_policy", false));
  METRO_ASSIGN_OR_RETURN(step, f.Number("step_fraction"));
  if (second) options.second_order = *second;
  if (truncate) options.truncate_dof = *truncate;
  if (step) options.step_fraction = *step;
  if (policy == "group" || policy.empty()) {
    options.correlated_dof = CorrelatedDofPolicy::kGroup;
  } else if (policy == "ignore") {
    options.correlated_dof = CorrelatedDofPolicy::kIgnore;
  } else if (policy == "reject") {
    options.correlated_dof = CorrelatedDofPolicy::kReject;
  } else {
    return f.Fail("unknown dof_policy '" + policy + "' (expected group, ignore or reject)");
  }
  return options;
}

Result<McOptions> ParseMcOptions(const json& object, const std::string& path, double coverage) {
  McOptions options;
  options.coverage = coverage;
  if (object.is_null()) {
    options.adaptive = true;  // No settings: the adaptive procedure decides M.
    return options;
  }
  if (object.is_boolean()) {
    options.enabled = object.get<bool>();
    options.adaptive = true;
    return options;
  }
  if (!object.is_object()) return MakeError(path, 0, "'monte_carlo' must be an object or false");
  Fields f(object, "monte_carlo", path);
  if (auto s =
          f.OnlyKeys({"trials", "seed", "adaptive", "ndig", "max_trials", "threads", "enabled"});
      !s.ok()) {
    return s.error();
  }
  METRO_ASSIGN_OR_RETURN(trials, f.Integer("trials"));
  METRO_ASSIGN_OR_RETURN(seed, f.Integer("seed"));
  METRO_ASSIGN_OR_RETURN(adaptive, f.Bool("adaptive"));
  METRO_ASSIGN_OR_RETURN(ndig, f.Integer("ndig"));
  METRO_ASSIGN_OR_RETURN(max_trials, f.Integer("max_trials"));
  METRO_ASSIGN_OR_RETURN(threads, f.Integer("threads"));
  METRO_ASSIGN_OR_RETURN(enabled, f.Bool("enabled"));
  if (trials) options.trials = *trials;
  if (seed) {
    if (*seed < 0) return f.Fail("'seed' must be >= 0");
    options.seed = static_cast<uint64_t>(*seed);
  }
  // Without 'trials' the adaptive procedure is used; 'adaptive' overrides.
  options.adaptive = adaptive ? *adaptive : !trials.has_value();
  if (ndig) options.ndig = static_cast<int>(*ndig);
  if (max_trials) options.max_trials = *max_trials;
  if (threads) options.threads = static_cast<int>(*threads);
  if (enabled) options.enabled = *enabled;
  std::string why;
  if (!options.IsValid(&why)) return f.Fail(why);
  return options;
}

}  // namespace

const char* DistributionName(Distribution distribution) {
  switch (distribution) {
    case Distribution::kNormal:
      return "normal";
    case Distribution::kRectangular:
      return "rectangular";
    case Distribution::kTriangular:
      return "triangular";
    case Distribution::kArcsine:
      return "arcsine";
    case Distribution::kTrapezoidal:
      return "trapezoidal";
    case Distribution::kCurvilinearTrapezoid:
      return "ctrap";
    case Distribution::kStudentT:
      return "t";
    case Distribution::kTypeA:
      return "type_a";
  }
  return "?";
}

const char* CorrelatedDofPolicyName(CorrelatedDofPolicy policy) {
  switch (policy) {
    case CorrelatedDofPolicy::kGroup:
      return "group";
    case CorrelatedDofPolicy::kIgnore:
      return "ignore";
    case CorrelatedDofPolicy::kReject:
      return "reject";
  }
  return "?";
}

bool GumOptions::IsValid(std::string* why) const {
  if (!(coverage > 0.0 && coverage < 1.0)) {
    *why = "coverage must be in (0, 1), got " + std::to_string(coverage);
    return false;
  }
  if (!(step_fraction > 0.0 && step_fraction <= 1.0)) {
    *why = "step_fraction must be in (0, 1]";
    return false;
  }
  return true;
}

bool McOptions::IsValid(std::string* why) const {
  if (!(coverage > 0.0 && coverage < 1.0)) {
    *why = "coverage must be in (0, 1), got " + std::to_string(coverage);
    return false;
  }
  if (!adaptive && trials < 2) {
    *why = "trials must be at least 2";
    return false;
  }
  // The same cap for both: the adaptive run keeps every trial too (JCGM 101 7.9), so a
  // max_trials beyond it would grow until memory runs out.
  constexpr int64_t kMaxStoredTrials = 500000000;
  if (!adaptive && trials > kMaxStoredTrials) {
    *why = "trials must be at most 5e8 (memory: 8 bytes per trial)";
    return false;
  }
  if (adaptive && max_trials > kMaxStoredTrials) {
    *why = "max_trials must be at most 5e8 (memory: 8 bytes per trial), got " +
           std::to_string(max_trials);
    return false;
  }
  if (ndig < 1 || ndig > 6) {
    *why = "ndig must be in 1..6";
    return false;
  }
  if (adaptive && max_trials < 10 * 10000) {
    *why = "max_trials must allow at least 10 blocks of 1e4 trials";
    return false;
  }
  if (threads < 0 || threads > 256) {
    *why = "threads must be in 0..256";
    return false;
  }
  return true;
}

namespace internal {

Error ModelError(const Budget& budget, const Error& model_error) {
  const size_t at =
      model_error.column > 0 ? static_cast<size_t>(model_error.column - 1) : std::string::npos;
  const std::string& what = model_error.message;
  const bool reads_on =
      what.rfind("uses ", 0) == 0 || what.rfind("evaluates ", 0) == 0 || what.rfind("is ", 0) == 0;
  const char* join = reads_on ? " " : what.rfind("column ", 0) == 0 ? ", " : ": ";
  const std::string message = "model '" + Excerpt(budget.model, at) + "'" + join + what;
  if (budget.model_line == 0) return MakeError(budget.file, 0, message);
  // JSON strings hold no line break: the byte's line is the opening quote's.
  const size_t offset = at == std::string::npos ? 0 : JsonStringByteOffset(budget.model_json, at);
  return MakeError(budget.file, budget.model_line,
                   budget.model_column + static_cast<int64_t>(offset), message);
}

Error ModelError(const Budget& budget, const std::string& what) {
  return ModelError(budget, MakeError(what));
}

std::string QuotedModel(const Budget& budget) { return "'" + Excerpt(budget.model) + "'"; }

}  // namespace internal

Status ValidateBudget(const Budget& budget) {
  const std::string& path = budget.file;
  std::string why;
  if (!budget.gum.IsValid(&why)) return MakeError(path, 0, "gum options: " + why);
  if (!budget.monte_carlo.IsValid(&why)) return MakeError(path, 0, "monte_carlo: " + why);
  if (budget.inputs.empty()) return MakeError(path, 0, "the budget has no inputs");
  std::map<std::string, size_t> index;
  for (size_t i = 0; i < budget.inputs.size(); ++i) {
    const BudgetInput& in = budget.inputs[i];
    if (!index.emplace(in.name, i).second) {
      return MakeError(path, 0, "input '" + in.name + "' is defined twice");
    }
    if (!std::isfinite(in.value)) return MakeError(path, 0, "input '" + in.name + "': value");
    if (!(in.u >= 0.0) || !std::isfinite(in.u)) {
      return MakeError(path, 0,
                       "input '" + in.name + "': u must be >= 0, got " + std::to_string(in.u));
    }
    if (!(in.dof > 0.0)) {
      return MakeError(path, 0, "input '" + in.name + "': dof must be > 0");
    }
  }
  // Correlations (JCGM 100 5.2.2): known names, |r| <= 1, positive definite matrix.
  std::vector<size_t> involved;
  std::map<std::pair<size_t, size_t>, double> r;
  for (const Correlation& c : budget.correlations) {
    const auto a = index.find(c.a);
    const auto b = index.find(c.b);
    if (a == index.end() || b == index.end()) {
      return MakeError(path, 0,
                       "correlation " + c.a + "/" + c.b + ": input '" +
                           (a == index.end() ? c.a : c.b) + "' is not defined");
    }
    if (a->second == b->second) {
      return MakeError(path, 0, "correlation of input '" + c.a + "' with itself");
    }
    if (!(std::fabs(c.r) <= 1.0)) {
      return MakeError(
          path, 0,
          "correlation " + c.a + "/" + c.b + ": |r| must be <= 1, got " + std::to_string(c.r));
    }
    const auto key = std::minmax(a->second, b->second);
    if (r.count(key)) {
      return MakeError(path, 0, "correlation " + c.a + "/" + c.b + " is given twice");
    }
    r[key] = c.r;
    for (size_t k : {a->second, b->second}) {
      if (std::find(involved.begin(), involved.end(), k) == involved.end()) involved.push_back(k);
    }
  }
  std::sort(involved.begin(), involved.end());
  if (!involved.empty()) {
    const Eigen::Index m = static_cast<Eigen::Index>(involved.size());
    Eigen::MatrixXd matrix = Eigen::MatrixXd::Identity(m, m);
    for (const auto& [key, value] : r) {
      const auto ia = std::find(involved.begin(), involved.end(), key.first) - involved.begin();
      const auto ib = std::find(involved.begin(), involved.end(), key.second) - involved.begin();
      matrix(ia, ib) = matrix(ib, ia) = value;
    }
    // The first leading minor that fails names the input that breaks positive definiteness.
    for (Eigen::Index k = 1; k <= m; ++k) {
      Eigen::LLT<Eigen::MatrixXd> llt(matrix.topLeftCorner(k, k));
      if (llt.info() != Eigen::Success) {
        const std::string name = budget.inputs[involved[static_cast<size_t>(k - 1)]].name;
        return MakeError(path, 0,
                         "the correlation matrix is not positive definite: input '" + name +
                             "' is inconsistent with its correlations to the inputs before it "
                             "(check r values; |r| = 1 is not allowed)");
      }
    }
  }
  // The model.
  std::vector<std::string> names;
  std::vector<double> x;
  for (const auto& in : budget.inputs) {
    names.push_back(in.name);
    x.push_back(in.value);
  }
  if (budget.model.empty()) {
    for (const auto& in : budget.inputs) {
      if (!in.sensitivity) {
        return MakeError(
            path, 0,
            "input '" + in.name + "': missing 'sensitivity' (needed when the budget has no model)");
      }
    }
    if (auto units = CheckBudgetUnits(budget); !units.ok()) return units.error();
    return Status();
  }
  for (const auto& in : budget.inputs) {
    if (in.sensitivity) {
      return MakeError(path, 0,
                       "input '" + in.name +
                           "': 'sensitivity' is only for budgets without a model (with a "
                           "model it is computed)");
    }
  }
  auto model = internal::MeasurementModel::FromExpression(budget.model, names);
  if (!model.ok()) return internal::ModelError(budget, model.error());
  const double y = model.value().Evaluate(x.data());
  if (!std::isfinite(y)) {
    return internal::ModelError(budget,
                                "evaluates to " + std::to_string(y) + " at the input estimates");
  }
  if (auto units = CheckBudgetUnits(budget); !units.ok()) return units.error();
  return Status();
}

Result<BudgetUnits> CheckBudgetUnits(const Budget& budget) {
  const std::string& path = budget.file;
  BudgetUnits result;
  std::vector<std::optional<PhysicalUnit>> units;
  bool any = false;
  for (const BudgetInput& in : budget.inputs) {
    if (in.unit.empty()) {
      units.emplace_back();
      continue;
    }
    auto u = PhysicalUnit::Parse(in.unit);
    if (!u.ok()) return MakeError(path, 0, "input '" + in.name + "': " + u.error().message);
    units.emplace_back(u.value());
    any = true;
  }
  std::optional<PhysicalUnit> measurand;
  if (!budget.unit.empty()) {
    auto u = PhysicalUnit::Parse(budget.unit);
    if (!u.ok()) {
      return MakeError(path, 0, "measurand '" + budget.measurand + "': " + u.error().message);
    }
    measurand = u.value();
  }
  if (!any) {
    result.note = "no input states a unit: units not checked";
    return result;
  }
  if (budget.model.empty()) {
    result.note =
        "no model: each sensitivity c_i is in (measurand unit)/(input unit); units parsed, not "
        "compared";
    return result;
  }
  std::vector<std::string> names;
  std::vector<double> x;
  for (const BudgetInput& in : budget.inputs) {
    names.push_back(in.name);
    x.push_back(in.value);
  }
  auto model = internal::MeasurementModel::FromExpression(budget.model, names);
  if (!model.ok()) return internal::ModelError(budget, model.error());
  auto checked =
      internal::CheckModelUnits(budget.model, names, units, x, model.value().Evaluate(x.data()));
  if (!checked.ok()) return internal::ModelError(budget, checked.error());
  const internal::ModelUnit& m = checked.value();
  result.checked = true;
  result.scale_known = m.scale_known && !m.constant;
  result.model_unit = m.constant ? std::string() : m.unit.ToString();
  if (measurand && !m.constant && m.unit.SameAs(*measurand)) result.model_unit = budget.unit;
  if (measurand && !m.constant) {
    const std::optional<UnitConversion> c = m.unit.ConversionTo(*measurand);
    if (!c) {
      // At the model's opening quote (no position for a budget built in code).
      return MakeError(path, budget.model_line, budget.model_column,
                       "measurand '" + budget.measurand + "' is declared in '" + budget.unit +
                           "' but the model " + internal::QuotedModel(budget) + " gives " +
                           m.unit.ToString() + " (" + m.unit.Definition() +
                           "): incompatible dimensions");
    }
    if (m.scale_known && !c->IsIdentity()) {
      return MakeError(path, budget.model_line, budget.model_column,
                       fmt::format("measurand '{}' is declared in '{}' but the model {} gives "
                                   "{} (1 {} = {:.6g} {}{}): declare the measurand in the "
                                   "model's unit or convert the model with a factor",
                                   budget.measurand, budget.unit, internal::QuotedModel(budget),
                                   m.unit.ToString(), m.unit.ToString(), c->factor, budget.unit,
                                   c->offset != 0.0 ? fmt::format(" + {:.6g}", c->offset) : ""));
    }
  }
  result.note = m.constant ? "the model uses no input"
                : result.scale_known
                    ? "model checked by unit"
                    : "model checked by dimension (a constant factor may convert the scale)";
  return result;
}

Result<Budget> ParseBudget(const std::string& json_text, const std::string& budget_path,
                           const SessionQuantityResolver& resolver) {
  Result<json> parsed = ParseJsonText(json_text, budget_path);
  if (!parsed.ok()) return parsed.error();
  json root = std::move(parsed).value();
  if (!root.is_object()) return MakeError(budget_path, 0, "a budget must be a JSON object");
  Budget budget;
  budget.file = budget_path;
  Fields top(root, "budget", budget_path);
  if (auto s = top.OnlyKeys({"measurand", "inputs", "correlations", "coverage", "monte_carlo",
                             "gum", "description", "schema"});
      !s.ok()) {
    return s.error();
  }
  if (!root.contains("measurand") || !root.at("measurand").is_object()) {
    return MakeError(budget_path, 0, "missing 'measurand' object");
  }
  Fields m(root.at("measurand"), "measurand", budget_path);
  if (auto s = m.OnlyKeys({"name", "unit", "model", "description"}); !s.ok()) return s.error();
  METRO_ASSIGN_OR_RETURN(mname, m.String("name", true));
  METRO_ASSIGN_OR_RETURN(munit, m.String("unit", false));
  METRO_ASSIGN_OR_RETURN(model, m.String("model", false));
  METRO_ASSIGN_OR_RETURN(description, top.String("description", false));
  budget.measurand = mname;
  budget.unit = munit;
  budget.model = model;
  if (!model.empty()) {
    // Where the model is written, for errors at its byte (budget.hpp).
    const size_t at = JsonValueOffset(json_text, {std::string("measurand"), std::string("model")});
    if (at < json_text.size() && json_text[at] == '"') {
      size_t end = at + 1;
      while (end < json_text.size() && json_text[end] != '"') end += json_text[end] == '\\' ? 2 : 1;
      budget.model_json = json_text.substr(at, std::min(end + 1, json_text.size()) - at);
      std::tie(budget.model_line, budget.model_column) = TextLineColumn(json_text, at);
    }
  }
  budget.description = description;
  METRO_ASSIGN_OR_RETURN(coverage_opt, top.Number("coverage"));
  const double coverage = coverage_opt ? *coverage_opt : 0.95;
  if (!(coverage > 0.0 && coverage < 1.0)) {
    return MakeError(budget_path, 0,
                     "'coverage' must be in (0, 1), got " + std::to_string(coverage));
  }
  if (!root.contains("inputs") || !root.at("inputs").is_array()) {
    return MakeError(budget_path, 0, "missing 'inputs' array");
  }
  const json& inputs = root.at("inputs");
  for (size_t i = 0; i < inputs.size(); ++i) {
    METRO_ASSIGN_OR_RETURN(input, ParseInput(inputs[i], i, budget_path, resolver));
    budget.inputs.push_back(std::move(input));
  }
  if (root.contains("correlations")) {
    const json& cs = root.at("correlations");
    if (!cs.is_array()) return MakeError(budget_path, 0, "'correlations' must be an array");
    for (size_t i = 0; i < cs.size(); ++i) {
      if (!cs[i].is_object()) {
        return MakeError(budget_path, 0,
                         "correlations[" + std::to_string(i) + "] must be an object");
      }
      Fields c(cs[i], "correlations[" + std::to_string(i) + "]", budget_path);
      if (auto s = c.OnlyKeys({"a", "b", "r"}); !s.ok()) return s.error();
      METRO_ASSIGN_OR_RETURN(a, c.String("a", true));
      METRO_ASSIGN_OR_RETURN(b, c.String("b", true));
      METRO_ASSIGN_OR_RETURN(rv, c.RequiredNumber("r", "correlation coefficient"));
      budget.correlations.push_back({a, b, rv});
    }
  }
  METRO_ASSIGN_OR_RETURN(gum, ParseGumOptions(root.value("gum", json()), budget_path, coverage));
  budget.gum = gum;
  METRO_ASSIGN_OR_RETURN(mc,
                         ParseMcOptions(root.value("monte_carlo", json()), budget_path, coverage));
  budget.monte_carlo = mc;
  if (auto s = ValidateBudget(budget); !s.ok()) return s.error();
  return budget;
}

Result<Budget> LoadBudget(const std::string& path, const SessionQuantityResolver& resolver) {
  auto text = ReadFile(path);
  if (!text.ok()) return text.error();
  return ParseBudget(text.value(), path, resolver);
}

std::vector<std::string> SessionsNamedInBudget(const std::string& budget_path) {
  std::vector<std::string> sessions;
  Result<std::string> text = ReadFile(budget_path);
  if (!text.ok()) return sessions;
  Result<json> root = ParseJsonText(text.value(), budget_path);
  if (!root.ok() || !root.value().is_object() || !root.value().contains("inputs") ||
      !root.value().at("inputs").is_array()) {
    return sessions;
  }
  for (const json& input : root.value().at("inputs")) {
    if (!input.is_object() || !input.contains("type_a")) continue;
    const json& type_a = input.at("type_a");
    if (!type_a.is_object() || !type_a.contains("session") || !type_a.at("session").is_string()) {
      continue;
    }
    std::string session = type_a.at("session").get<std::string>();
    if (session.empty()) continue;
    if (session[0] != '/') session = DirectoryOf(budget_path) + session;
    sessions.push_back(std::move(session));
  }
  return sessions;
}

}  // namespace metro
