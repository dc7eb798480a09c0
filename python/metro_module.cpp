// `import metro`: the library as a Python module (pybind11), a thin layer on top like apps/:
// each call converts its arguments, calls the library function the CLI calls, and returns a
// typed result whose to_json() is the CLI's JSON byte for byte (docs/python.md).
//
// One translation unit on purpose: pybind11 costs seconds of compiler CPU per file.
//
// Conventions:
// - Arrays in: a 1-D C-contiguous numpy.ndarray of float64, read in place (no copy) where the
//   library reads a pointer (metro.allan); anything else is a ValueError naming the argument.
// - Arrays out: read-only views of the library's vectors, kept alive by the object they came
//   from (Session.tag(...).t_s).
// - Errors: metro.Error with kind ("input", "failed", "io"), file, line, column and message;
//   metro.InputError is also a ValueError, FailedError a RuntimeError, IoError an OSError.
// - Long calls run on a worker thread with the GIL released; the calling thread checks for
//   signals every 50 ms and on Ctrl-C sets the call's CancelFlag (metro/core/cancel.hpp), joins
//   the worker and raises KeyboardInterrupt.
#include <pybind11/eval.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "metro/blob/blob.hpp"
#include "metro/blob/from_calibration.hpp"
#include "metro/blob/inspect.hpp"
#include "metro/calibration/calibrate.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/calibration/imu_model.hpp"
#include "metro/core/cancel.hpp"
#include "metro/core/status.hpp"
#include "metro/core/utc_time.hpp"
#include "metro/core/version.hpp"
#include "metro/io/columns.hpp"
#include "metro/io/session.hpp"
#include "metro/io/session_io.hpp"
#include "metro/io/tag_registry.hpp"
#include "metro/noise/allan.hpp"
#include "metro/noise/allan_report.hpp"
#include "metro/noise/noise_model.hpp"
#include "metro/registry/registry.hpp"
#include "metro/report/allan_section.hpp"
#include "metro/report/session_analysis.hpp"
#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/budget_report.hpp"
#include "metro/uncertainty/session_resolver.hpp"

namespace py = pybind11;

namespace metro::python {
namespace {

// The module, for its exception classes (set once at import).
py::handle g_module;

// --- Errors ---------------------------------------------------------------------------------

constexpr const char* kExceptionClasses = R"(
class Error(Exception):
    """A metro error: str() is "file:line:column: message" as the CLI prints it; kind is
    "input" (bad input or usage, the CLI's exit 2), "failed" (the work failed on valid input,
    exit 1) or "io" (a write failed, exit 1)."""
    def __init__(self, text, kind, file="", line=0, column=0, message=""):
        super().__init__(text)
        self.kind = kind
        self.file = file
        self.line = line
        self.column = column
        self.message = message or text

class InputError(Error, ValueError):
    """Bad input or usage (ErrorKind::kInput)."""

class FailedError(Error, RuntimeError):
    """The work failed on valid input (ErrorKind::kFailed)."""

class IoError(Error, OSError):
    """A write failed after it started (ErrorKind::kIo)."""

class ClosedError(Error, ValueError):
    """An object used after the registry it came from was closed."""
)";

[[noreturn]] void RaiseClass(const char* cls_name, const Error& error) {
  py::object cls = g_module.attr(cls_name);
  py::object exc = cls(error.ToString(), ErrorKindName(error.kind), error.file, error.line,
                       error.column, error.message);
  PyErr_SetObject(cls.ptr(), exc.ptr());
  throw py::error_already_set();
}

[[noreturn]] void Raise(const Error& error) {
  switch (error.kind) {
    case ErrorKind::kInput:
      RaiseClass("InputError", error);
    case ErrorKind::kFailed:
      RaiseClass("FailedError", error);
    case ErrorKind::kIo:
      RaiseClass("IoError", error);
  }
  RaiseClass("Error", error);
}

template <typename T>
T Value(Result<T> result) {
  if (!result.ok()) Raise(result.error());
  return std::move(result).value();
}

// --- Long calls -----------------------------------------------------------------------------

// Runs fn() on a worker thread with the GIL released and returns its result; Ctrl-C
// (a pending KeyboardInterrupt, checked every 50 ms from the main thread) cancels it through
// its CancelFlag and raises KeyboardInterrupt once the worker has returned. fn must not touch
// Python objects.
template <typename Fn>
auto RunReleased(Fn&& fn) -> decltype(fn()) {
  using R = decltype(fn());
  CancelFlag flag;
  std::optional<R> result;
  std::exception_ptr failure;
  std::mutex mutex;
  std::condition_variable done_cv;
  bool done = false;
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    std::thread worker([&] {
      ScopedCancel scope(&flag);
      try {
        result.emplace(fn());
      } catch (...) {
        failure = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex);
      done = true;
      done_cv.notify_one();
    });
    std::unique_lock<std::mutex> lock(mutex);
    while (!done_cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; })) {
      if (interrupted) continue;
      lock.unlock();
      {
        py::gil_scoped_acquire acquire;
        // Runs the Python signal handlers (main thread only): Ctrl-C leaves KeyboardInterrupt
        // set here, raised below once the worker has stopped.
        if (PyErr_CheckSignals() != 0) interrupted = true;
      }
      if (interrupted) flag.Cancel();
      lock.lock();
    }
    lock.unlock();
    worker.join();
  }
  if (interrupted) throw py::error_already_set();
  if (failure != nullptr) {
    try {
      std::rethrow_exception(failure);
    } catch (const Cancelled&) {
      PyErr_SetNone(PyExc_KeyboardInterrupt);
      throw py::error_already_set();
    }
  }
  return std::move(*result);
}

// --- Arrays ---------------------------------------------------------------------------------

// `obj` as a 1-D C-contiguous float64 array (not copied), or a ValueError naming `name`.
py::array_t<double> DoubleArray(py::handle obj, const std::string& name) {
  const std::string expected =
      "expected a 1-D C-contiguous numpy.ndarray of float64 (numpy.ascontiguousarray(" + name +
      ", dtype=numpy.float64))";
  if (!py::isinstance<py::array>(obj)) {
    throw py::value_error(name + ": " +
                          py::str(py::type::of(obj).attr("__name__")).cast<std::string>() +
                          " given; " + expected);
  }
  py::array a = py::reinterpret_borrow<py::array>(obj);
  if (a.ndim() != 1) {
    throw py::value_error(name + ": an array of " + std::to_string(a.ndim()) + " dimensions; " +
                          expected);
  }
  if (!py::isinstance<py::array_t<double>>(obj) && !a.dtype().is(py::dtype::of<double>())) {
    throw py::value_error(name + ": dtype " + py::str(a.dtype()).cast<std::string>() + "; " +
                          expected);
  }
  if ((a.flags() & py::array::c_style) == 0) {
    throw py::value_error(name + ": not contiguous (a strided view, stride " +
                          std::to_string(a.strides(0)) + " bytes); " + expected);
  }
  return py::reinterpret_borrow<py::array_t<double>>(obj);
}

// The first non-finite element of a, or -1.
int64_t FirstNonFinite(const double* a, int64_t n) {
  for (int64_t i = 0; i < n; ++i) {
    if (!std::isfinite(a[i])) return i;
  }
  return -1;
}

// A read-only view of `v`, kept alive by `owner`.
template <typename T>
py::array View(const std::vector<T>& v, py::handle owner) {
  py::array a(py::dtype::of<T>(), {static_cast<py::ssize_t>(v.size())},
              {static_cast<py::ssize_t>(sizeof(T))}, v.data(), owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// A copy of `v` as a new array (for results held by value).
template <typename T>
py::array Copy(const std::vector<T>& v) {
  return py::array_t<T>(static_cast<py::ssize_t>(v.size()), v.data());
}

std::string PathText(py::handle path) {
  return py::str(py::module_::import("os").attr("fspath")(path));
}

py::object JsonLoads(const std::string& text) {
  return py::module_::import("json").attr("loads")(text);
}

// What the CLI prints as a warning, as RuntimeWarnings.
void IssueWarnings(const std::vector<std::string>& lines) {
  py::object warn = py::module_::import("warnings").attr("warn");
  for (const std::string& line : lines)
    warn(line, py::module_::import("builtins").attr("RuntimeWarning"), 2);
}

// --- Sessions -------------------------------------------------------------------------------

using SessionPtr = std::shared_ptr<const Session>;

// One tag of a session; keeps the session alive for the arrays it hands out.
struct TagView {
  SessionPtr session;
  size_t index = 0;
  const Tag& tag() const { return session->tags[index]; }
};

const Tag& FindTagOrRaise(const Session& s, std::optional<int> sensor) {
  if (s.tags.empty()) throw py::value_error("the session has no tag");
  if (!sensor) return s.tags.front();
  const Tag* t = s.FindTag(*sensor);
  if (t == nullptr) {
    std::string have;
    for (const Tag& tag : s.tags) have += (have.empty() ? "" : ", ") + std::to_string(tag.sensor);
    throw py::key_error("sensor " + std::to_string(*sensor) + ": not in the session (sensors " +
                        have + ")");
  }
  return *t;
}

LoadOptions MakeLoadOptions(const std::string& format, bool lenient, double rate_hz,
                            const std::vector<std::string>& columns,
                            const std::string& columns_file, const std::vector<std::string>& topics,
                            double accel_fs_g, double gyro_fs_dps, const std::string& time,
                            const std::string& time_order, std::optional<double> frame_period_s,
                            int threads) {
  LoadOptions load;
  if (!ParseSessionFormat(format, &load.format)) {
    Raise(MakeError("format=" + format +
                    ": unknown format (auto, csv, receiver, imutk, euroc, raw, phyphox, "
                    "sensorlogger, phone, ulog, mcap, rosbag1, rosbag2, dataflash)"));
  }
  load.lenient = lenient;
  load.rate_hz = rate_hz;
  load.accel_fs_g = accel_fs_g;
  load.gyro_fs_dps = gyro_fs_dps;
  load.topics = topics;
  if (time != "header" && time != "receive") {
    Raise(MakeError("time=" + time + ": expected header or receive"));
  }
  load.ros_time =
      time == "receive" ? LoadOptions::RosTime::kReceive : LoadOptions::RosTime::kHeader;
  if (time_order != "sort" && time_order != "refuse") {
    Raise(MakeError("time_order=" + time_order + ": expected sort or refuse"));
  }
  load.time_order =
      time_order == "refuse" ? LoadOptions::TimeOrder::kRefuse : LoadOptions::TimeOrder::kSort;
  if (frame_period_s) load.frame_period_s = *frame_period_s;
  load.threads = threads;
  if (!columns_file.empty()) load.column_map = Value(LoadColumnMappings(columns_file));
  for (const std::string& spec : columns) {
    load.column_map.push_back(Value(ParseColumnMapping(spec)));
  }
  std::string why;
  if (!load.IsValid(&why)) Raise(MakeError(why));
  return load;
}

// Session.from_arrays: one tag from a time array and named columns, checked as the loaders
// check a file (canonical names, finite values, strictly increasing times).
SessionPtr SessionFromArrays(py::handle t_obj, const py::dict& columns, int sensor) {
  py::array_t<double> t = DoubleArray(t_obj, "t");
  const int64_t n = t.shape(0);
  if (n < 1) throw py::value_error("t: empty; at least one observation is needed");
  const double* tp = t.data();
  if (int64_t bad = FirstNonFinite(tp, n); bad >= 0) {
    throw py::value_error("t: element " + std::to_string(bad) + " is " +
                          py::str(py::float_(tp[bad])).cast<std::string>() +
                          "; times must be finite (the loaders refuse such a row)");
  }
  for (int64_t i = 1; i < n; ++i) {
    if (!(tp[i] > tp[i - 1])) {
      throw py::value_error("t: element " + std::to_string(i) + " (" + std::to_string(tp[i]) +
                            " s) is not after element " + std::to_string(i - 1) + " (" +
                            std::to_string(tp[i - 1]) + " s); times must strictly increase");
    }
  }
  if (columns.empty())
    throw py::value_error("columns: empty; give at least one, e.g. {\"gx_dps\": arr}");
  auto session = std::make_shared<Session>();
  session->path = "<arrays>";
  session->rows = n;
  Tag tag;
  tag.sensor = sensor;
  tag.t_s.assign(tp, tp + n);
  tag.line.resize(static_cast<size_t>(n));
  for (int64_t i = 0; i < n; ++i) tag.line[static_cast<size_t>(i)] = static_cast<uint32_t>(i + 2);
  session->columns.push_back("t_s");
  for (auto item : columns) {
    const std::string name = py::str(item.first);
    const std::string arg = "columns[\"" + name + "\"]";
    if (!IsValidColumnName(name)) {
      throw py::value_error(arg + ": not a column name ([a-z][a-z0-9_]*, e.g. gx_dps)");
    }
    const ColumnInfo info = ClassifyColumn(name);
    if (info.role == ColumnRole::kTime || info.role == ColumnRole::kSensor ||
        info.role == ColumnRole::kText) {
      throw py::value_error(arg + ": a " +
                            std::string(info.role == ColumnRole::kTime     ? "time"
                                        : info.role == ColumnRole::kSensor ? "sensor"
                                                                           : "text") +
                            " column; give times as t and one tag per session");
    }
    py::array_t<double> a = DoubleArray(item.second, arg);
    if (a.shape(0) != n) {
      throw py::value_error(arg + ": " + std::to_string(a.shape(0)) + " values for " +
                            std::to_string(n) + " times");
    }
    const double* ap = a.data();
    for (int64_t i = 0; i < n; ++i) {
      if (!std::isfinite(ap[i]) && !(info.allow_empty && std::isnan(ap[i]))) {
        throw py::value_error(arg + ": element " + std::to_string(i) + " is " +
                              py::str(py::float_(ap[i])).cast<std::string>() +
                              "; values must be finite (the loaders refuse such a field)");
      }
    }
    Quantity q;
    q.name = name;
    q.unit = info.UnitSymbol();
    q.origin =
        info.role == ColumnRole::kQuantity ? QuantityOrigin::kFile : QuantityOrigin::kUnknown;
    q.values.assign(ap, ap + n);
    tag.quantities.push_back(std::move(q));
    session->columns.push_back(name);
    if (info.role == ColumnRole::kUnknown) session->unknown_columns.push_back(name);
  }
  session->input.time_source = "t_s";
  session->input.header_line = 1;
  session->input.header_names = session->columns;
  // yaw_deg, pitch_deg, roll_deg from qw..qz, as the loaders derive them.
  if (std::string w = DeriveEulerIfAbsent(&tag); !w.empty()) {
    session->input.warnings.push_back(w);
    IssueWarnings({w});
  }
  session->tags.push_back(std::move(tag));
  return session;
}

// --- Results --------------------------------------------------------------------------------

const SensorReport& FindSensorOrRaise(const SessionReport& report, std::optional<int64_t> sensor) {
  if (report.sensors.empty()) throw py::key_error("the report has no sensor");
  const SensorReport* s = sensor ? report.FindSensor(*sensor) : &report.sensors.front();
  if (s == nullptr)
    throw py::key_error("sensor " + std::to_string(*sensor) + ": not in the report");
  return *s;
}

const QuantityReport& FindQuantityOrRaise(const SessionReport& report, const std::string& quantity,
                                          std::optional<int64_t> sensor) {
  const QuantityReport* q = FindSensorOrRaise(report, sensor).Find(quantity);
  if (q == nullptr) throw py::key_error(quantity + ": not in the report");
  return *q;
}

// What a session analysis produced (metro.type_a).
struct PyReport {
  SessionReport report;
  std::string table;
  std::vector<std::string> failures;
  std::vector<std::string> warnings;
  bool nothing_produced = false;
};

struct PyAllan {
  AllanReport report;
  std::string unit;
  uintptr_t input_address = 0;  // The address the library read the samples from.
};

struct PyBudget {
  BudgetReport report;
  std::string table;
  std::vector<std::string> warnings;
};

// The noise terms as {"random_walk": AllanNoiseTermReport, ...}.
py::dict NoiseTerms(const AllanReport& r) {
  py::dict d;
  for (size_t i = 0; i < kNoiseTermCount; ++i) {
    d[py::str(NoiseTermKey(static_cast<NoiseTerm>(i)))] = r.noise[i];
  }
  return d;
}

SessionAnalysisOptions MakeAnalysisOptions(
    const std::string& settle, const std::string& settle_scope, int64_t skip_samples,
    double skip_seconds, std::optional<double> from_s, std::optional<double> to_s,
    const std::vector<int>& sensors, const std::vector<std::string>& quantities, bool allan,
    const std::string& taus, const std::string& estimator, const std::string& gaps,
    const std::string& budget, const std::string& tags, int threads) {
  SessionAnalysisOptions o;
  if (settle != "none" && settle != "auto")
    Raise(MakeError("settle=" + settle + ": expected none or auto"));
  if (settle_scope != "quantity" && settle_scope != "tag") {
    Raise(MakeError("settle_scope=" + settle_scope + ": expected quantity or tag"));
  }
  WindowOptions& w = o.type_a.window;
  w.settle_auto = settle == "auto";
  w.settle_tag_wide = settle_scope == "tag";
  w.skip_samples = skip_samples;
  w.skip_seconds = skip_seconds;
  w.from_s = from_s;
  w.to_s = to_s;
  o.type_a.sensors = sensors;
  o.type_a.quantities = quantities;
  o.type_a.threads = threads;
  o.load.threads = threads;
  o.plot.threads = threads;
  if (!tags.empty()) o.registry = Value(TagRegistry::Load(tags));
  if (allan) {
    o.allan = true;
    o.allan_options.allan.taus = Value(ParseTauSpacing(taus));
    o.allan_options.allan.estimator = Value(ParseAllanEstimator(estimator));
    o.allan_options.gaps = Value(ParseAllanGapPolicy(gaps));
    o.allan_options.allan.threads = threads;
    o.allan_options.quantities = quantities;
  }
  o.budget_path = budget;
  std::string why;
  if (!o.IsValid(&why)) Raise(MakeError(why));
  return o;
}

PyReport Analyze(py::handle source, const SessionAnalysisOptions& options) {
  SessionAnalysis analysis;
  if (py::isinstance<Session>(source)) {
    SessionPtr s = source.cast<SessionPtr>();
    analysis = RunReleased([&] { return AnalyzeLoadedSession(*s, options); });
  } else {
    const std::string path = PathText(source);
    analysis = RunReleased([&] { return AnalyzeSession(path, options); });
  }
  if (!analysis.ok) Raise(analysis.error);
  PyReport out{std::move(analysis.report), std::move(analysis.table), std::move(analysis.failures),
               std::move(analysis.warnings), analysis.nothing_produced};
  IssueWarnings(out.failures);
  IssueWarnings(out.warnings);
  return out;
}

PyAllan Allan(py::handle x_obj, double tau0_s, const std::string& estimator,
              const std::string& taus, const std::vector<int64_t>& m, int64_t max_m,
              double confidence, const std::string& unit, int threads) {
  py::array_t<double> x = DoubleArray(x_obj, "x");
  AllanOptions options;
  options.estimator = Value(ParseAllanEstimator(estimator));
  options.taus = Value(ParseTauSpacing(taus));
  options.m_list = m;
  options.max_m = max_m;
  options.confidence = confidence;
  options.threads = threads;
  const double* data = x.data();
  const int64_t n = x.shape(0);
  Result<AllanCurve> curve = RunReleased([&] { return ComputeAllan(data, n, tau0_s, options); });
  if (!curve.ok()) Raise(curve.error().WithContext("x"));
  PyAllan out;
  out.unit = unit;
  out.input_address = reinterpret_cast<uintptr_t>(data);
  // The fit as the session report makes it (AllanReportOfCurve); the sample period is the
  // stated grid.
  out.report = AllanReportOfCurve(curve.value(), NoiseFitOptions{}, unit);
  out.report.sample_period.tau0_s = tau0_s;
  out.report.sample_period.rate_hz = 1.0 / tau0_s;
  out.report.sample_period.mean_dt_s = tau0_s;
  out.report.sample_period.jitter_rms_s = 0.0;
  out.report.sample_period.max_abs_jitter_s = 0.0;
  return out;
}

PyBudget EvaluateBudgetFrom(py::handle source) {
  Result<Budget> budget = MakeError("no budget");
  const SessionQuantityResolver resolver = MakeSessionQuantityResolver("", {}, {});
  if (py::isinstance<py::dict>(source)) {
    const std::string text = py::module_::import("json").attr("dumps")(source).cast<std::string>();
    budget = RunReleased([&] { return ParseBudget(text, "<dict>", resolver); });
  } else {
    const std::string path = PathText(source);
    budget = RunReleased([&] { return LoadBudget(path, resolver); });
  }
  if (!budget.ok()) Raise(budget.error());
  const Budget& b = budget.value();
  Result<BudgetEvaluation> evaluation =
      RunReleased([&] { return EvaluateBudget(b, /*progress=*/nullptr); });
  if (!evaluation.ok()) Raise(evaluation.error());
  const BudgetEvaluation& e = evaluation.value();
  PyBudget out;
  out.report = MakeBudgetReport(e);
  out.table = BudgetReportTable(out.report);
  for (const std::string& w : e.gum.warnings) out.warnings.push_back(w);
  IssueWarnings(out.warnings);
  if (!e.ok) {
    Raise(
        MakeFailedError(e.monte_carlo ? e.monte_carlo->message : std::string("evaluation failed")));
  }
  return out;
}

// --- Calibration, blob, registry ------------------------------------------------------------

// The sessions of `source`: a path, a metro.Session, an (ACC, GYRO) tuple of imu_tk files, or
// a list of them (loaded as the CLI loads SESSION arguments and --imutk pairs, with the default
// options).
std::vector<SessionPtr> SessionsOf(py::handle source) {
  std::vector<py::object> items;
  if (py::isinstance<py::list>(source)) {
    items = source.cast<std::vector<py::object>>();
  } else {
    items.push_back(py::reinterpret_borrow<py::object>(source));
  }
  std::vector<SessionPtr> out;
  for (const py::object& item : items) {
    if (py::isinstance<Session>(item)) {
      out.push_back(item.cast<std::shared_ptr<Session>>());
    } else if (py::isinstance<py::tuple>(item)) {
      const auto files = item.cast<std::vector<py::object>>();
      if (files.size() != 2) {
        throw py::value_error("sessions: a tuple of " + std::to_string(files.size()) +
                              " items; an imu_tk input is (ACC, GYRO), two files");
      }
      const std::string acc = PathText(files[0]), gyro = PathText(files[1]);
      out.push_back(
          std::make_shared<Session>(Value(RunReleased([&] { return LoadImuTk(acc, gyro); }))));
    } else {
      const std::string path = PathText(item);
      out.push_back(std::make_shared<Session>(
          Value(RunReleased([&] { return LoadSession(path, LoadOptions{}); }))));
    }
  }
  if (out.empty()) throw py::value_error("sessions: empty; give a path or a metro.Session");
  return out;
}

// A calibration.json model: fitted here, or loaded.
struct PyCalibration {
  Calibration calibration;
};

Calibration CalibrationOf(py::handle source) {
  if (py::isinstance<PyCalibration>(source)) return source.cast<const PyCalibration&>().calibration;
  const std::string path = PathText(source);
  return Value(LoadCalibration(path));
}

// A model keyword (model, accel_model, gyro_model) as `calibrate fit` takes it.
ModelKind ModelKindOf(const std::string& arg, const std::string& value, const char* expected) {
  const std::optional<ModelKind> kind = ParseModelKind(value);
  if (!kind) Raise(MakeError(arg + "=" + value + ": expected " + expected));
  return *kind;
}

// `calibrate fit`'s options from the keywords, as fit_flags.hpp maps the flags: `model` sets
// both sensors' model unless accel_model / gyro_model names its own; accel_model "none" fits
// no accelerometer (the gyroscope's bias at rest, with gyro_model "bias").
CalibrationOptions FitOptionsOf(const std::string& model, int sensor,
                                const std::optional<std::string>& accel_model,
                                const std::optional<std::string>& gyro_model,
                                const std::string& loss, double loss_scale, bool accel_only,
                                std::optional<double> min_static_s) {
  CalibrationOptions options;
  options.compare_models = true;  // `calibrate fit` always compares the model ladder.
  options.accel_auto = options.gyro_auto = model == "auto";
  if (model != "auto") {
    options.accel_model = options.gyro_model =
        ModelKindOf("model", model, "auto, bias, scale or full");
  }
  if (accel_model) {
    options.accel_auto = *accel_model == "auto";
    if (*accel_model == "none") {
      options.fit_accel = false;
    } else if (*accel_model != "auto") {
      options.accel_model =
          ModelKindOf("accel_model", *accel_model, "auto, bias, scale, full or none");
    }
  }
  if (gyro_model) {
    options.gyro_auto = *gyro_model == "auto";
    if (*gyro_model != "auto") {
      options.gyro_model = ModelKindOf("gyro_model", *gyro_model, "auto, bias, scale or full");
    }
  }
  const std::optional<LossKind> loss_kind = ParseLossKind(loss);
  if (!loss_kind) Raise(MakeError("loss=" + loss + ": expected none, huber or cauchy"));
  options.loss = *loss_kind;
  options.loss_scale = loss_scale;
  if (accel_only) options.fit_gyro = false;
  if (min_static_s) options.segmentation.min_static_s = *min_static_s;
  options.sensor = sensor;
  return options;
}

PyCalibration Fit(py::handle sessions, const std::string& model, int sensor,
                  const std::optional<std::string>& accel_model,
                  const std::optional<std::string>& gyro_model, py::handle segments,
                  const std::string& loss, double loss_scale, bool accel_only,
                  std::optional<double> min_static_s, py::handle tags) {
  const CalibrationOptions options =
      Value(ResolveFitOptions(FitOptionsOf(model, sensor, accel_model, gyro_model, loss, loss_scale,
                                           accel_only, min_static_s),
                              segments.is_none() ? "" : PathText(segments)));
  const std::optional<TagRegistry> tag_file =
      tags.is_none() ? std::nullopt
                     : std::optional<TagRegistry>(Value(TagRegistry::Load(PathText(tags))));
  const std::vector<SessionPtr> loaded = SessionsOf(sessions);
  std::vector<const Session*> ptrs;
  for (const SessionPtr& s : loaded) ptrs.push_back(s.get());
  // Missing columns are bad input, named with the file before any fitting (as `calibrate fit`).
  Result<Calibration> cal = RunReleased([&]() -> Result<Calibration> {
    if (Status c = CheckCalibrationColumns(ptrs, options); !c.ok()) return c.error();
    return CalibrateSessions(ptrs, options);
  });
  PyCalibration out{Value(std::move(cal))};
  if (tag_file) NameFittedTags(*tag_file, &out.calibration);
  return out;
}

std::shared_ptr<Session> Apply(py::handle session, py::handle calibration,
                               std::optional<double> t_valid_min_c,
                               std::optional<double> t_valid_max_c) {
  const Calibration cal = CalibrationOf(calibration);
  SessionPtr in = SessionsOf(session).front();
  ApplyCalibrationOptions options;
  options.validity.t_valid_min_c = t_valid_min_c;
  options.validity.t_valid_max_c = t_valid_max_c;
  auto out = std::make_shared<Session>(*in);
  Result<ApplySummary> summary =
      RunReleased([&] { return ApplyCalibration(cal, out.get(), options); });
  IssueWarnings(Value(std::move(summary)).warnings);
  return out;
}

uint64_t DeviceIdOf(py::handle id) {
  if (py::isinstance<py::int_>(id)) return id.cast<uint64_t>();
  return Value(blob::ParseDeviceId(py::str(id).cast<std::string>()));
}

py::bytes BuildBlob(py::handle calibration, int sensor, py::handle device_id, uint32_t seq,
                    int dlpf_cfg, const std::string& profile, std::optional<double> t_valid_min_c,
                    std::optional<double> t_valid_max_c, bool accept_rejected_model) {
  const Calibration cal = CalibrationOf(calibration);
  blob::BlobFromCalibrationOptions o;
  o.sensor = sensor;
  o.device_id = DeviceIdOf(device_id);
  o.seq = seq;
  if (dlpf_cfg < 0 || dlpf_cfg > 6) Raise(MakeError("dlpf_cfg: expected 0..6"));
  o.dlpf_cfg = static_cast<uint8_t>(dlpf_cfg);
  const std::optional<blob::SensorProfile> p = blob::ParseSensorProfile(profile);
  if (!p) Raise(MakeError("profile=" + profile + ": expected mpu6050 or generic"));
  o.profile = *p;
  o.t_valid_min_c = t_valid_min_c;
  o.t_valid_max_c = t_valid_max_c;
  o.accept_rejected_model = accept_rejected_model;
  std::vector<std::string> warnings;
  blob::BlobContents contents = Value(blob::BlobContentsFromCalibration(cal, o, &warnings));
  IssueWarnings(warnings);
  const std::vector<uint8_t> bytes = Value(blob::WriteBlob(contents));
  return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

// An open registry; every call after close() raises metro.ClosedError, and what history()
// returns holds no reference to it.
struct PyRegistry {
  std::unique_ptr<Registry> registry;
  std::string url;
  Registry& Get() {
    if (!registry) {
      Error e = MakeError("registry " + url + " is closed");
      RaiseClass("ClosedError", e);
    }
    return *registry;
  }
};

}  // namespace
}  // namespace metro::python

namespace metro::python {
namespace {

// metro.Session, metro.Tag, metro.load.
void AddSessions(py::module_& m) {
  py::class_<TagView>(m, "Tag", "One tag of a session: times and quantities as read-only arrays")
      .def_property_readonly("sensor", [](const TagView& t) { return t.tag().sensor; })
      .def_property_readonly("source_name", [](const TagView& t) { return t.tag().source_name; })
      .def_property_readonly(
          "t_s", [](py::object self) { return View(self.cast<const TagView&>().tag().t_s, self); },
          "observation times [s] (a read-only view)")
      .def_property_readonly(
          "quantities",
          [](py::object self) {
            const Tag& tag = self.cast<const TagView&>().tag();
            py::dict d;
            for (const Quantity& q : tag.quantities) d[py::str(q.name)] = View(q.values, self);
            return d;
          },
          "{name: read-only array}, in file order")
      .def_property_readonly("units",
                             [](const TagView& t) {
                               py::dict d;
                               for (const Quantity& q : t.tag().quantities)
                                 d[py::str(q.name)] = q.unit;
                               return d;
                             })
      .def("__getitem__",
           [](py::object self, const std::string& name) {
             const Quantity* q = self.cast<const TagView&>().tag().Find(name);
             if (q == nullptr) throw py::key_error(name + ": no such quantity in this tag");
             return View(q->values, self);
           })
      .def("__len__", [](const TagView& t) { return t.tag().size(); })
      .def("__repr__", [](const TagView& t) {
        return "<metro.Tag sensor " + std::to_string(t.tag().sensor) + ", " +
               std::to_string(t.tag().size()) + " observations, " +
               std::to_string(t.tag().quantities.size()) + " quantities>";
      });

  py::class_<Session, std::shared_ptr<Session>>(m, "Session", "A loaded session (metro.load)")
      .def_static(
          "from_arrays",
          [](py::handle t, const py::dict& columns, int sensor) {
            return std::const_pointer_cast<Session>(SessionFromArrays(t, columns, sensor));
          },
          py::arg("t"), py::arg("columns"), py::kw_only(), py::arg("sensor") = 1,
          "One tag from times t [s] and {canonical column name: array}, e.g. {\"gx_dps\": x}")
      .def_readonly("path", &Session::path)
      .def_readonly("sha256", &Session::sha256)
      .def_readonly("rows", &Session::rows)
      .def_readonly("columns", &Session::columns)
      .def_property_readonly("format", [](const Session& s) { return SessionFormatName(s.format); })
      .def(
          "to_csv", [](const Session& s) { return FormatSessionCsv(s, true); },
          "canonical session.csv text, as `characterize convert` and `calibrate apply` write it")
      .def_property_readonly("sensors",
                             [](const Session& s) {
                               std::vector<int> v;
                               for (const Tag& t : s.tags) v.push_back(t.sensor);
                               return v;
                             })
      .def(
          "tag",
          [](std::shared_ptr<Session> s, std::optional<int> sensor) {
            const Tag& t = FindTagOrRaise(*s, sensor);
            return TagView{s, static_cast<size_t>(&t - s->tags.data())};
          },
          py::arg("sensor") = py::none(), "the tag of that sensor number (None: the first)")
      .def_property_readonly("tags",
                             [](std::shared_ptr<Session> s) {
                               std::vector<TagView> v;
                               for (size_t i = 0; i < s->tags.size(); ++i) v.push_back({s, i});
                               return v;
                             })
      .def("__repr__", [](const Session& s) {
        return "<metro.Session " + s.path + ": " + SessionFormatName(s.format) + ", " +
               std::to_string(s.tags.size()) + " tags>";
      });

  m.def(
      "load",
      [](py::handle path, const std::string& format, bool lenient, double rate_hz,
         const std::vector<std::string>& columns, const std::string& columns_file,
         const std::vector<std::string>& topics, double accel_fs_g, double gyro_fs_dps,
         const std::string& time, const std::string& time_order,
         std::optional<double> frame_period_s, int threads) {
        const LoadOptions load =
            MakeLoadOptions(format, lenient, rate_hz, columns, columns_file, topics, accel_fs_g,
                            gyro_fs_dps, time, time_order, frame_period_s, threads);
        Result<Session> session = MakeError("not loaded");
        if (py::isinstance<py::tuple>(path) || py::isinstance<py::list>(path)) {
          // imu_tk's two files, (ACC, GYRO).
          auto files = path.cast<std::vector<py::object>>();
          if (files.size() != 2)
            throw py::value_error("path: imu_tk input is (ACC, GYRO), two files");
          const std::string acc = PathText(files[0]), gyro = PathText(files[1]);
          session = RunReleased([&] { return LoadImuTk(acc, gyro, load); });
        } else {
          const std::string p = PathText(path);
          session = RunReleased([&] { return LoadSession(p, load); });
        }
        return std::make_shared<Session>(Value(std::move(session)));
      },
      py::arg("path"), py::kw_only(), py::arg("format") = "auto", py::arg("lenient") = false,
      py::arg("rate_hz") = 0.0, py::arg("columns") = std::vector<std::string>{},
      py::arg("columns_file") = "", py::arg("topics") = std::vector<std::string>{},
      py::arg("accel_fs_g") = 0.0, py::arg("gyro_fs_dps") = 0.0, py::arg("time") = "header",
      py::arg("time_order") = "sort", py::arg("frame_period_s") = py::none(),
      py::arg("threads") = 0,
      "Loads a session file in any format the CLI reads (the CLI's --format, --lenient, "
      "--rate-hz, --column SRC=DST, --columns-file, --topic, --accel-fs-g, --gyro-fs-dps, "
      "--time, --time-order, --frame-period-s); a (ACC, GYRO) pair is imu_tk input");
}

// metro.NoiseTerm, metro.Allan, metro.allan.
void AddAllan(py::module_& m) {
  py::class_<AllanNoiseTermReport>(m, "NoiseTerm", "An IEEE 952 noise term of an Allan fit")
      .def_readonly("value", &AllanNoiseTermReport::value)
      .def_readonly("u", &AllanNoiseTermReport::u)
      .def_readonly("unit", &AllanNoiseTermReport::unit)
      .def_readonly("value_conventional", &AllanNoiseTermReport::value_conventional)
      .def_readonly("u_conventional", &AllanNoiseTermReport::u_conventional)
      .def_readonly("unit_conventional", &AllanNoiseTermReport::unit_conventional)
      .def_readonly("supported", &AllanNoiseTermReport::supported)
      .def_readonly("tau_min_s", &AllanNoiseTermReport::tau_min_s)
      .def_readonly("tau_max_s", &AllanNoiseTermReport::tau_max_s)
      .def("__repr__", [](const AllanNoiseTermReport& t) {
        return t.supported ? "<metro.NoiseTerm " + std::to_string(t.value) + " +- " +
                                 std::to_string(t.u) + " " + t.unit + ">"
                           : std::string("<metro.NoiseTerm not supported by the fit>");
      });

  py::class_<PyAllan>(m, "Allan", "An Allan curve with intervals and IEEE 952 noise terms")
      .def_property_readonly("estimator", [](const PyAllan& a) { return a.report.estimator; })
      .def_property_readonly("tau_s", [](const PyAllan& a) { return Copy(a.report.tau_s); })
      .def_property_readonly(
          "adev", [](const PyAllan& a) { return Copy(a.report.adev); },
          "the estimator's deviation, in the unit of x")
      .def_property_readonly("ci_low", [](const PyAllan& a) { return Copy(a.report.ci_low); })
      .def_property_readonly("ci_high", [](const PyAllan& a) { return Copy(a.report.ci_high); })
      .def_property_readonly("edf", [](const PyAllan& a) { return Copy(a.report.edf); })
      .def_property_readonly("n_terms", [](const PyAllan& a) { return Copy(a.report.n_terms); })
      .def_property_readonly("alpha", [](const PyAllan& a) { return Copy(a.report.alpha); })
      .def_property_readonly("alpha_source", [](const PyAllan& a) { return a.report.alpha_source; })
      .def_property_readonly("confidence", [](const PyAllan& a) { return a.report.confidence; })
      .def_property_readonly("noise", [](const PyAllan& a) { return NoiseTerms(a.report); })
      .def_property_readonly("fit_error", [](const PyAllan& a) { return a.report.fit_error; })
      .def_readonly("input_address", &PyAllan::input_address,
                    "the address the samples were read from (x's own buffer: not copied)")
      .def(
          "to_json", [](const PyAllan& a) { return ToJson(a.report) + "\n"; },
          "the \"allan\" object of the CLI's report for this curve")
      .def("to_dict", [](const PyAllan& a) { return JsonLoads(ToJson(a.report)); });

  m.def("allan", &Allan, py::arg("x"), py::arg("tau0"), py::kw_only(),
        py::arg("estimator") = "oadev", py::arg("taus") = "octave",
        py::arg("m") = std::vector<int64_t>{}, py::arg("max_m") = 0, py::arg("confidence") = 0.683,
        py::arg("unit") = "", py::arg("threads") = 0,
        "Allan deviation of rate samples x (1-D float64, read in place) at period tau0 [s]: "
        "estimator oadev|mdev|ohdev|adev|hdev, taus octave|decade:K|all|every (or m=[...]), "
        "chi-squared intervals (NIST SP 1065 5.3.2) and IEEE 952 terms in `unit` (deg/s, rad/s, "
        "g, m/s^2)");
}

// metro.Report, metro.type_a.
void AddAnalysis(py::module_& m) {
  py::class_<TypeAReport>(m, "TypeA", "A quantity's GUM Type A result (JCGM 100 4.2)")
      .def_readonly("n", &TypeAReport::n)
      .def_readonly("mean", &TypeAReport::mean)
      .def_readonly("variance", &TypeAReport::variance)
      .def_readonly("std", &TypeAReport::std)
      .def_readonly("std_of_mean", &TypeAReport::std_of_mean)
      .def_readonly("dof", &TypeAReport::dof)
      .def_readonly("n_eff", &TypeAReport::n_eff)
      .def_readonly("std_of_mean_autocorr", &TypeAReport::std_of_mean_autocorr)
      .def_readonly("u_mean", &TypeAReport::u_mean,
                    "metro's recommended u(mean), autocorrelation included")
      .def_readonly("u_mean_dof", &TypeAReport::u_mean_dof)
      .def_readonly("u_mean_method", &TypeAReport::u_mean_method)
      .def_readonly("coverage", &TypeAReport::coverage)
      .def_readonly("k", &TypeAReport::k)
      .def_readonly("U_mean", &TypeAReport::U_mean)
      .def("__repr__", [](const TypeAReport& t) {
        return "<metro.TypeA n " + std::to_string(t.n) + ", mean " + std::to_string(t.mean) +
               ", u_mean " + std::to_string(t.u_mean) + ">";
      });

  py::class_<PyReport>(m, "Report", "A session report (metro.report/1), the CLI's JSON")
      .def(
          "to_json", [](const PyReport& r) { return ToJson(r.report) + "\n"; },
          "exactly the file `characterize SESSION --type-a -o FILE` writes")
      .def("to_dict", [](const PyReport& r) { return JsonLoads(ToJson(r.report)); })
      .def_readonly("table", &PyReport::table)
      .def_readonly("failures", &PyReport::failures)
      .def_readonly("warnings", &PyReport::warnings)
      .def_readonly("nothing_produced", &PyReport::nothing_produced)
      .def_property_readonly("sensors",
                             [](const PyReport& r) {
                               std::vector<int64_t> v;
                               for (const SensorReport& s : r.report.sensors) v.push_back(s.sensor);
                               return v;
                             })
      .def(
          "quantities",
          [](const PyReport& r, std::optional<int64_t> sensor) {
            std::vector<std::string> names;
            for (const QuantityReport& q : FindSensorOrRaise(r.report, sensor).quantities) {
              names.push_back(q.name);
            }
            return names;
          },
          py::arg("sensor") = py::none(), "the quantities of a tag (None: the first), in order")
      .def(
          "type_a",
          [](const PyReport& r, const std::string& quantity, std::optional<int64_t> sensor) {
            const QuantityReport& q = FindQuantityOrRaise(r.report, quantity, sensor);
            if (!q.type_a) Raise(MakeFailedError(quantity + ": " + q.error));
            return *q.type_a;
          },
          py::arg("quantity"), py::arg("sensor") = py::none(),
          "the Type A result of a quantity, as metro.TypeA")
      .def(
          "allan",
          [](const PyReport& r, const std::string& quantity, std::optional<int64_t> sensor) {
            const QuantityReport* q = &FindQuantityOrRaise(r.report, quantity, sensor);
            if (!q->allan) {
              throw py::key_error(quantity + ": no Allan section (type_a(..., allan=True))");
            }
            if (!q->allan->ok()) Raise(MakeFailedError(q->allan->error));
            return PyAllan{*q->allan, q->unit, 0};
          },
          py::arg("quantity"), py::arg("sensor") = py::none(),
          "the Allan section of a quantity, as metro.Allan");

  m.def(
      "type_a",
      [](py::handle session, const std::string& settle, const std::string& settle_scope,
         int64_t skip_samples, double skip_seconds, std::optional<double> from_s,
         std::optional<double> to_s, const std::vector<int>& sensors,
         const std::vector<std::string>& quantities, bool allan, const std::string& taus,
         const std::string& estimator, const std::string& gaps, py::object budget, py::object tags,
         int threads) {
        const SessionAnalysisOptions options = MakeAnalysisOptions(
            settle, settle_scope, skip_samples, skip_seconds, from_s, to_s, sensors, quantities,
            allan, taus, estimator, gaps, budget.is_none() ? "" : PathText(budget),
            tags.is_none() ? "" : PathText(tags), threads);
        return Analyze(session, options);
      },
      py::arg("session"), py::kw_only(), py::arg("settle") = "none",
      py::arg("settle_scope") = "quantity", py::arg("skip_samples") = 0,
      py::arg("skip_seconds") = 0.0, py::arg("from_s") = py::none(), py::arg("to_s") = py::none(),
      py::arg("sensors") = std::vector<int>{}, py::arg("quantities") = std::vector<std::string>{},
      py::arg("allan") = false, py::arg("taus") = "octave", py::arg("estimator") = "oadev",
      py::arg("gaps") = "skip", py::arg("budget") = py::none(), py::arg("tags") = py::none(),
      py::arg("threads") = 0,
      "GUM Type A of every tag and quantity (JCGM 100 4.2) with a u(mean) that survives "
      "autocorrelation; allan=True adds the Allan sections, budget=PATH a budget on the "
      "session. session: a path (as the CLI) or a metro.Session. The CLI's --settle, "
      "--settle-scope, --skip-samples, --skip-seconds, --from-s, --to-s, --sensor, --quantity, "
      "--allan, --taus, --estimator, --gaps, --budget, --tags, --threads");
}

// metro.Budget, metro.budget.
void AddBudget(py::module_& m) {
  py::class_<PyBudget>(m, "Budget", "An evaluated uncertainty budget (metro.budget-report/1)")
      .def(
          "to_json", [](const PyBudget& b) { return ToJson(b.report) + "\n"; },
          "exactly the file `characterize budget BUDGET -o FILE` writes")
      .def("to_dict", [](const PyBudget& b) { return JsonLoads(ToJson(b.report)); })
      .def_readonly("table", &PyBudget::table)
      .def_readonly("warnings", &PyBudget::warnings)
      .def_property_readonly("value", [](const PyBudget& b) { return b.report.result.value; })
      .def_property_readonly("u", [](const PyBudget& b) { return b.report.result.u; })
      .def_property_readonly("k", [](const PyBudget& b) { return b.report.result.k; })
      .def_property_readonly("U", [](const PyBudget& b) { return b.report.result.expanded; })
      .def_property_readonly("coverage", [](const PyBudget& b) { return b.report.result.coverage; })
      .def_property_readonly("dof_eff", [](const PyBudget& b) { return b.report.result.dof_eff; })
      .def_property_readonly("unit", [](const PyBudget& b) { return b.report.measurand.unit; })
      .def_property_readonly("statement",
                             [](const PyBudget& b) { return b.report.result.statement; })
      .def_property_readonly("monte_carlo", [](const PyBudget& b) -> py::object {
        if (!b.report.monte_carlo) return py::none();
        return JsonLoads(ToJson(b.report))["monte_carlo"];
      });
}

// metro.calibrate, metro.blob, metro.registry.
void AddCalibration(py::module_& m) {
  py::module_ calibrate = m.def_submodule("calibrate", "Ceres calibration (`calibrate fit|apply`)");
  py::class_<PyCalibration>(calibrate, "Calibration", "A calibration.json model")
      .def(
          "to_json", [](const PyCalibration& c) { return FormatCalibrationJson(c.calibration); },
          "exactly the calibration.json `calibrate fit SESSION -o FILE` writes")
      .def("to_dict",
           [](const PyCalibration& c) { return JsonLoads(FormatCalibrationJson(c.calibration)); })
      .def_property_readonly("sensors", [](const PyCalibration& c) {
        std::vector<int> v;
        for (const TagCalibration& t : c.calibration.tags) v.push_back(t.sensor);
        return v;
      });
  calibrate.def(
      "load", [](py::handle path) { return PyCalibration{CalibrationOf(path)}; }, py::arg("path"),
      "reads a calibration.json");
  calibrate.def("fit", &Fit, py::arg("sessions"), py::kw_only(), py::arg("model") = "auto",
                py::arg("sensor") = 0, py::arg("accel_model") = py::none(),
                py::arg("gyro_model") = py::none(), py::arg("segments") = py::none(),
                py::arg("loss") = "none", py::arg("loss_scale") = 3.0,
                py::arg("accel_only") = false, py::arg("min_static_s") = py::none(),
                py::arg("tags") = py::none(),
                "Fits every tag (or `sensor`) of the calibration session(s) (paths, "
                "metro.Session, (ACC, GYRO) imu_tk pairs, or a list of them), as `calibrate fit "
                "SESSION... -o calibration.json` with the flags --model, --sensor, "
                "--accel-model (auto|bias|scale|full|none), --gyro-model, --segments FILE, "
                "--loss (none|huber|cauchy), --loss-scale, --accel-only, --min-static-s, "
                "--tags FILE and --imutk (the pairs)");
  calibrate.def("apply", &Apply, py::arg("session"), py::arg("calibration"), py::kw_only(),
                py::arg("t_valid_min_c") = py::none(), py::arg("t_valid_max_c") = py::none(),
                "A new session with the calibration applied, as `calibrate apply`");

  py::module_ blobm =
      m.def_submodule("blob", "The firmware's calibration blob (`calibrate blob|inspect`)");
  blobm.def(
      "build", &BuildBlob, py::arg("calibration"), py::kw_only(), py::arg("sensor"),
      py::arg("device_id"), py::arg("seq") = 1, py::arg("dlpf_cfg") = 3,
      py::arg("profile") = "mpu6050", py::arg("t_valid_min_c") = py::none(),
      py::arg("t_valid_max_c") = py::none(), py::arg("accept_rejected_model") = false,
      "The blob's bytes, as `calibrate blob CALIBRATION --sensor N --device-id ID -o tag.bin`");
  blobm.def(
      "inspect",
      [](py::handle source, py::object device_id) {
        blob::InspectOptions o;
        if (!device_id.is_none()) o.device_id = DeviceIdOf(device_id);
        blob::InspectReport r;
        if (py::isinstance<py::bytes>(source)) {
          const std::string b = source.cast<std::string>();
          r = blob::InspectBin(std::vector<uint8_t>(b.begin(), b.end()), o);
        } else {
          r = Value(blob::InspectFile(PathText(source), o));
        }
        return JsonLoads(blob::ToJson(r));
      },
      py::arg("blob"), py::kw_only(), py::arg("device_id") = py::none(),
      "The firmware validator's verdict on a tag.bin / tag.hex (path) or blob bytes, as the "
      "dict `calibrate inspect FILE --json` prints");

  py::module_ registry =
      m.def_submodule("registry", "The calibration registry (`calibrate registry`)");
  py::class_<PyRegistry>(registry, "Registry", "An open registry (SQLite file or PostgreSQL)")
      .def(
          "history",
          [](PyRegistry& r, py::handle device_id) {
            const uint64_t id = DeviceIdOf(device_id);
            Registry& reg = r.Get();
            auto h = Value(RunReleased([&] { return reg.History(id); }));
            return JsonLoads(HistoryToJson(id, h));
          },
          py::arg("device_id"),
          "A device's calibrations, blobs and pushes: the dict `calibrate registry history "
          "--device-id ID --json` prints")
      .def(
          "drift",
          [](PyRegistry& r, py::handle device_id) {
            const uint64_t id = DeviceIdOf(device_id);
            Registry& reg = r.Get();
            const DriftResult d = Value(RunReleased([&] { return reg.Drift(id); }));
            if (d.shared_inputs) {
              IssueWarnings(
                  {"the two calibrations share an input record (same SHA-256): their covariance "
                   "is not 0, so u_change is overstated and |E_n| understated"});
            }
            return JsonLoads(ToJson(d));
          },
          py::arg("device_id"),
          "The change of every constant between a device's last two calibrations: the dict "
          "`calibrate registry drift --device-id ID --json` prints")
      .def(
          "due",
          [](PyRegistry& r, double interval_days, std::optional<std::string> at_utc, bool all) {
            if (!(interval_days > 0) || !std::isfinite(interval_days)) {
              Raise(MakeError(
                  "interval_days=" + py::str(py::float_(interval_days)).cast<std::string>() +
                  ": expected a number > 0"));
            }
            const std::string now = at_utc ? *at_utc : UtcIso8601Now();
            if (!ParseUtcIso8601(now)) {
              Raise(MakeError("at_utc='" + now +
                              "': expected ISO 8601 UTC, e.g. 2026-05-01T12:00:00Z"));
            }
            Registry& reg = r.Get();
            Result<std::vector<DueDevice>> due =
                RunReleased([&] { return reg.Due(interval_days, now, all); });
            if (!due.ok()) Raise(due.error().WithKind(ErrorKind::kFailed));
            return JsonLoads(DueToJson(now, interval_days, due.value()));
          },
          py::arg("interval_days") = kDefaultRecalibrationIntervalDays,
          py::arg("at_utc") = py::none(), py::arg("all") = false,
          "The devices due for recalibration at at_utc (ISO 8601; None: now), all=True every "
          "device with its due date: the dict `calibrate registry due --interval-days D [--at "
          "T] [--all] --json` prints")
      .def(
          "export",
          [](PyRegistry& r, const std::string& format) -> py::object {
            if (format != "csv" && format != "json") {
              Raise(MakeError("format=" + format + ": expected csv or json"));
            }
            Registry& reg = r.Get();
            Result<std::vector<RegistryCalibration>> all = RunReleased([&] { return reg.All(); });
            if (!all.ok()) Raise(all.error().WithKind(ErrorKind::kFailed));
            if (format == "json") return JsonLoads(ExportToJson(reg.schema_version(), all.value()));
            return py::str(ExportToCsv(all.value()));
          },
          py::arg("format") = "csv",
          "Every calibration: the CSV text (str) `calibrate registry export` writes, or for "
          "format=\"json\" the dict of `calibrate registry export --format json`")
      .def("close", [](PyRegistry& r) { r.registry.reset(); })
      .def_property_readonly("closed", [](const PyRegistry& r) { return !r.registry; })
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](PyRegistry& r, py::args) { r.registry.reset(); });
  registry.def(
      "open",
      [](const std::string& url) {
        return PyRegistry{Value(RunReleased([&] { return Registry::OpenForQuery(url); })), url};
      },
      py::arg("url"), "Opens a registry for queries (sqlite:PATH or postgresql://...)");

  m.def("budget", &EvaluateBudgetFrom, py::arg("budget"),
        "Evaluates an uncertainty budget (a path, or a dict in the budget format, "
        "docs/budget-format.md): GUM with exact sensitivities (JCGM 100), adaptive Monte Carlo "
        "(JCGM 101) and the GUF validation, as `characterize budget`");
}

}  // namespace
}  // namespace metro::python

PYBIND11_MODULE(metro, m) {
  using namespace metro;
  using namespace metro::python;
  m.doc() =
      "metro: GUM Type A/B, Monte Carlo (JCGM 101), Allan deviation (IEEE 952), "
      "calibration and registry of IMU tags; the library the characterize and calibrate "
      "programs call (docs/python.md)";
  m.attr("__version__") = kVersion;
  g_module = m;
  py::exec(kExceptionClasses, m.attr("__dict__"));
  AddSessions(m);
  AddAllan(m);
  AddAnalysis(m);
  AddBudget(m);
  AddCalibration(m);
}
