#include "metro/calibration/gyro_bias.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "calibration/calibrate_stages.hpp"
#include "metro/stats/type_a.hpp"

namespace metro {

namespace ci = calibration_internal;

namespace {

// The three gyroscope axes of `tag` (the family FindFamily picks), checked finite.
Result<std::vector<std::vector<double>>> GyroAxes(const Tag& tag, std::string* unit) {
  const ci::FamilyMatch match = ci::FindFamily(tag, ImuSensor::kGyro);
  if (match.unit == nullptr) {
    return MakeError(match.family.empty()
                         ? fmt::format("sensor {}: no gyroscope columns: a bias at rest needs {}",
                                       tag.sensor, ci::FamilyChoices(ImuSensor::kGyro))
                         : ci::IncompleteFamilyMessage(tag.sensor, ImuSensor::kGyro, match));
  }
  std::vector<std::vector<double>> axes(3);
  for (int a = 0; a < 3; ++a) {
    const Quantity* q = tag.Find(match.family[static_cast<size_t>(a)]);
    for (size_t i = 0; i < q->values.size(); ++i) {
      if (!std::isfinite(q->values[i])) {
        return MakeError(
            "", tag.line.size() > i ? tag.line[i] : 0,
            fmt::format("sensor {}: {}: expected a finite number", tag.sensor, q->name));
      }
    }
    axes[static_cast<size_t>(a)] = q->values;
  }
  *unit = std::string(match.unit->symbol);
  return axes;
}

}  // namespace

Status CheckGyroRestRecords(const std::vector<const Session*>& sessions,
                            const CalibrationOptions& options) {
  std::map<int, std::string> seen;  // sensor -> its session
  for (const Session* s : sessions) {
    for (const Tag& t : s->tags) {
      if (options.sensor != 0 && t.sensor != options.sensor) continue;
      if (seen.count(t.sensor) != 0) {
        return MakeError(s->path, 0,
                         fmt::format("sensor {}: a bias at rest is evaluated from one static "
                                     "record; {} has one already (give one SESSION, or --sensor)",
                                     t.sensor, seen[t.sensor]));
      }
      seen[t.sensor] = s->path;
      std::string unit;
      Result<std::vector<std::vector<double>>> axes = GyroAxes(t, &unit);
      if (!axes.ok()) {
        Error e = axes.error();
        e.file = s->path;
        return e;
      }
      const size_t n = axes.value()[0].size();
      if (n < kMinRestSamples) {
        return MakeError(s->path, 0,
                         fmt::format("sensor {}: {} samples; a bias at rest needs at least {} "
                                     "(a static record of some seconds)",
                                     t.sensor, n, kMinRestSamples));
      }
      // Motion: a 1 s moving mean away from the record's mean, in deg/s.
      const double per_dps =
          1.0 / NominalScale(ImuSensor::kGyro, unit, options.gyro_fs_dps).value();
      const double span_s = t.t_s.back() - t.t_s.front();
      const size_t w = std::clamp<size_t>(
          static_cast<size_t>(std::lround(static_cast<double>(n - 1) / std::max(span_s, 1e-9))), 1,
          n);
      for (int a = 0; a < 3; ++a) {
        const std::vector<double>& v = axes.value()[static_cast<size_t>(a)];
        double mean = 0;
        for (double x : v) mean += x;
        mean /= static_cast<double>(n);
        double sum = 0;
        for (size_t i = 0; i < n; ++i) {
          sum += v[i];
          if (i >= w) sum -= v[i - w];
          if (i + 1 < w) continue;
          const double off_dps = (sum / static_cast<double>(w) - mean) / per_dps;
          if (std::abs(off_dps) > kRestLimitDps) {
            return MakeError(
                s->path, t.line.size() > i ? t.line[i] : 0,
                fmt::format("sensor {}: the record is not at rest: the 1 s mean of {} axis {} "
                            "differs from the record's mean by {:.2f} deg/s at t = {:.2f} s "
                            "(limit {} deg/s); a bias at rest needs the tag still throughout "
                            "(cut the record, or fit a multi-pose session)",
                            t.sensor, ImuSensorLongName(ImuSensor::kGyro), "xyz"[a], off_dps,
                            t.t_s[i], kRestLimitDps));
          }
        }
      }
    }
  }
  if (seen.empty()) {
    return MakeError(sessions.empty() ? "" : sessions.front()->path, 0,
                     options.sensor != 0
                         ? fmt::format("no tag with sensor number {} in the input", options.sensor)
                         : std::string("the input has no tags"));
  }
  return Status::Ok();
}

Result<TagCalibration> CalibrateGyroBiasAtRest(const std::vector<const Tag*>& records,
                                               const CalibrationOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) return MakeError("invalid calibration options: " + why);
  if (o.fit_accel || o.gyro_model != ModelKind::kBias) {
    return MakeError("a bias at rest takes fit_accel false and the gyroscope model bias");
  }
  if (records.size() != 1) {
    return MakeError(
        fmt::format("a bias at rest is evaluated from one static record, not {}", records.size()));
  }
  const Tag& tag = *records.front();
  std::string unit;
  Result<std::vector<std::vector<double>>> axes = GyroAxes(tag, &unit);
  if (!axes.ok()) return axes.error();
  const size_t n = axes.value()[0].size();
  if (n < kMinRestSamples) {
    return MakeError(fmt::format("sensor {}: {} samples; a bias at rest needs at least {}",
                                 tag.sensor, n, kMinRestSamples));
  }
  TagCalibration out;
  out.sensor = tag.sensor;
  SensorCalibration g;
  g.model.sensor = ImuSensor::kGyro;
  g.model.kind = ModelKind::kBias;
  g.model.input_unit = unit;
  g.model.output_unit = std::string(OutputUnit(ImuSensor::kGyro).symbol);
  const double nominal = NominalScale(ImuSensor::kGyro, unit, o.gyro_fs_dps).value();
  g.model.scale = Eigen::Vector3d::Constant(nominal);
  g.model.misalignment.assign(static_cast<size_t>(MisalignmentCount(ImuSensor::kGyro)), 0.0);
  g.covariance = Eigen::MatrixXd::Zero(3, 3);
  g.parameter_names = {"b_x", "b_y", "b_z"};
  double dof = std::numeric_limits<double>::infinity();
  double var_sum = 0;
  for (int a = 0; a < 3; ++a) {
    const std::vector<double>& v = axes.value()[static_cast<size_t>(a)];
    Result<TypeAResult> ta = EvaluateTypeA(v.data(), v.size());
    if (!ta.ok()) return ta.error();
    const TypeAResult& r = ta.value();
    if (!r.u_mean_available) {
      // A constant axis: the readings' resolution (1 count for raw data) bounds the mean, a
      // rectangular distribution of half-width 0.5 LSB (JCGM 100:2008 4.3.7, F.2.2.1).
      g.covariance(a, a) = 0.25 / 3.0;
      out.warnings.push_back(fmt::format(
          "sensor {}: gyroscope axis {} is constant over the record ({} {}): its u is the "
          "resolution's (0.5 count, rectangular)",
          tag.sensor, "xyz"[a], r.mean, unit));
    } else {
      g.covariance(a, a) = r.u_mean * r.u_mean;
      dof = std::min(dof, r.u_mean_dof);
      if (r.drift_detected) {
        out.warnings.push_back(fmt::format(
            "sensor {}: gyroscope axis {} drifts over the record (batch means scatter {:.3g} {} "
            "against the noise's {:.3g}): its u is the batch means' (docs/type-a.md)",
            tag.sensor, "xyz"[a], r.u_mean_batch, unit, r.u_mean_ar));
      }
    }
    g.model.bias[a] = r.mean;
    var_sum += r.variance;
  }
  DeriveUncertainties(&g);
  g.dof = std::isfinite(dof) ? std::max(1, static_cast<int>(std::floor(dof))) : 1;
  g.coverage_factor_95 = ci::StudentT975(g.dof);
  g.reduced_chi2 = 1.0;  // One mean per axis: no redundancy to test a model against.
  const double sample_rms_dps = std::sqrt(var_sum / 3.0) * nominal;
  g.residual_rms = sample_rms_dps;
  g.residual_unit = "deg/s";
  g.groups.push_back({"static_rate", 1, sample_rms_dps, "deg/s"});
  Segment seg;
  seg.kind = SegmentKind::kStatic;
  seg.begin = 0;
  seg.end = n;
  seg.start_s = tag.t_s.front();
  seg.end_s = tag.t_s.back();
  seg.pose = 1;
  g.segments.push_back(seg);
  out.segments.push_back(seg);
  if (const Quantity* temp = tag.Find("temp_c"); temp != nullptr) {
    double tmin = std::numeric_limits<double>::infinity(), tmax = -tmin, tsum = 0;
    size_t count = 0;
    for (double t : temp->values) {
      if (!std::isfinite(t)) continue;
      tmin = std::min(tmin, t);
      tmax = std::max(tmax, t);
      tsum += t;
      ++count;
    }
    if (count > 0) {
      // One pose: its mean temperature is the calibration's condition (min = mean = max).
      const double mean_c = tsum / static_cast<double>(count);
      g.static_pose_temperature = PoseTemperatureRange{mean_c, mean_c, mean_c, 1};
      if (tmax - tmin > 2.0) {
        out.warnings.push_back(fmt::format(
            "sensor {}: temp_c spans {:.2f} .. {:.2f} degC over the record; the bias at rest "
            "is the mean over that span (no temperature term is fitted from one pose)",
            tag.sensor, tmin, tmax));
      }
    }
  }
  out.gyro = std::move(g);
  return out;
}

}  // namespace metro
