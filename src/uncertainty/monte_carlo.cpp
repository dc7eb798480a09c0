#include "metro/uncertainty/monte_carlo.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <boost/random/normal_distribution.hpp>
#include <cmath>
#include <map>
#include <mutex>
#include <pcg_random.hpp>
#include <thread>

#include "uncertainty/model.hpp"

namespace metro {
namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

uint64_t SplitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Uniform on [0, 1) with 53 random bits (JCGM 101 C.3).
inline double Uniform(pcg64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }
// Uniform on (0, 1).
inline double UniformOpen(pcg64& rng) {
  return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
}

// Gamma(alpha, 1), Marsaglia and Tsang, ACM TOMS 26 (2000) 363-372; alpha < 1 through
// Gamma(alpha + 1) U^(1/alpha).
struct GammaSampler {
  explicit GammaSampler(double alpha_in = 1.0)
      : alpha(alpha_in), d((alpha_in < 1.0 ? alpha_in + 1.0 : alpha_in) - 1.0 / 3.0) {
    c = 1.0 / std::sqrt(9.0 * d);
  }
  double operator()(pcg64& rng, boost::random::normal_distribution<double>& normal) const {
    double g;
    for (;;) {
      const double z = normal(rng);
      double v = 1.0 + c * z;
      if (v <= 0.0) continue;
      v = v * v * v;
      const double u = UniformOpen(rng);
      const double z2 = z * z;
      if (u < 1.0 - 0.0331 * z2 * z2 || std::log(u) < 0.5 * z2 + d * (1.0 - v + std::log(v))) {
        g = d * v;
        break;
      }
    }
    if (alpha < 1.0) g *= std::pow(UniformOpen(rng), 1.0 / alpha);
    return g;
  }
  double alpha;
  double d;
  double c = 0.0;
};

// How one input (or one correlated group) is drawn.
struct InputPlan {
  enum class Kind {
    kConstant,
    kNormal,
    kT,
    kRectangular,
    kTriangular,
    kArcsine,
    kTrapezoidal,
    kCtrap,
    kGroupMember
  };
  Kind kind = Kind::kConstant;
  double value = 0.0;  // Location (centre).
  double scale = 0.0;  // u or t scale.
  double a = 0.0;      // Half-width.
  double beta = 0.0;
  double d = 0.0;
  double dof = 0.0;
  GammaSampler gamma;
};

struct GroupPlan {
  std::vector<size_t> members;  // Input indices, increasing.
  Eigen::MatrixXd cholesky;     // Lower factor of the correlation matrix.
  double dof = 0.0;             // Finite: multivariate t (shared chi-square), else normal.
  GammaSampler gamma;
};

struct Plan {
  std::vector<InputPlan> inputs;
  std::vector<GroupPlan> groups;
  std::vector<int> group_of;  // -1 or index in groups; the group is drawn at its first member.
  const internal::MeasurementModel* model = nullptr;
  uint64_t seed = 0;
};

Result<Plan> MakePlan(const Budget& budget) {
  Plan plan;
  const size_t n = budget.inputs.size();
  plan.inputs.resize(n);
  plan.group_of.assign(n, -1);
  std::map<std::string, size_t> index;
  for (size_t i = 0; i < n; ++i) index[budget.inputs[i].name] = i;
  for (size_t i = 0; i < n; ++i) {
    const BudgetInput& in = budget.inputs[i];
    InputPlan& p = plan.inputs[i];
    p.value = in.value;
    p.a = in.half_width;
    p.beta = in.beta;
    p.d = in.d;
    p.dof = in.dof;
    switch (in.distribution) {
      case Distribution::kNormal:
      case Distribution::kTypeA:
      case Distribution::kStudentT:
        p.scale = in.distribution == Distribution::kStudentT ? in.scale : in.u;
        // JCGM 101 6.4.7 (normal); 6.4.9 (t_nu(x, s^2) for Type A and for a standard
        // uncertainty stated with finite degrees of freedom).
        p.kind = std::isfinite(in.dof) ? InputPlan::Kind::kT : InputPlan::Kind::kNormal;
        if (p.kind == InputPlan::Kind::kT) p.gamma = GammaSampler(0.5 * in.dof);
        if (p.scale == 0.0) p.kind = InputPlan::Kind::kConstant;
        break;
      case Distribution::kRectangular:
        p.kind = InputPlan::Kind::kRectangular;
        break;
      case Distribution::kTriangular:
        p.kind = InputPlan::Kind::kTriangular;
        break;
      case Distribution::kArcsine:
        p.kind = InputPlan::Kind::kArcsine;
        break;
      case Distribution::kTrapezoidal:
        p.kind = InputPlan::Kind::kTrapezoidal;
        break;
      case Distribution::kCurvilinearTrapezoid:
        p.kind = InputPlan::Kind::kCtrap;
        break;
    }
    if (in.distribution != Distribution::kNormal && in.distribution != Distribution::kTypeA &&
        in.distribution != Distribution::kStudentT && in.half_width == 0.0) {
      p.kind = InputPlan::Kind::kConstant;
    }
  }
  // Correlated inputs: connected components of the non-zero correlations, JCGM 101 6.4.8.
  std::vector<size_t> parent(n);
  for (size_t i = 0; i < n; ++i) parent[i] = i;
  const auto root = [&](size_t i) {
    while (parent[i] != i) i = parent[i];
    return i;
  };
  std::vector<std::vector<double>> r(n, std::vector<double>(n, 0.0));
  for (const auto& c : budget.correlations) {
    if (c.r == 0.0) continue;
    const size_t a = index.at(c.a);
    const size_t b = index.at(c.b);
    if (budget.inputs[a].u == 0.0 || budget.inputs[b].u == 0.0) continue;
    r[a][b] = r[b][a] = c.r;
    parent[root(a)] = root(b);
  }
  std::map<size_t, std::vector<size_t>> components;
  for (size_t i = 0; i < n; ++i) components[root(i)].push_back(i);
  for (const auto& [key, members] : components) {
    (void)key;
    if (members.size() < 2) continue;
    GroupPlan g;
    g.members = members;
    const double dof0 = budget.inputs[members[0]].dof;
    for (size_t i : members) {
      const BudgetInput& in = budget.inputs[i];
      const bool normal_like = in.distribution == Distribution::kNormal ||
                               in.distribution == Distribution::kTypeA ||
                               in.distribution == Distribution::kStudentT;
      if (!normal_like) {
        return MakeError(budget.file, 0,
                         "input '" + in.name + "' is correlated but " +
                             DistributionName(in.distribution) +
                             ": JCGM 101 6.4.8 gives a joint distribution only for normal (or "
                             "t with common dof) inputs");
      }
      if (!(in.dof == dof0 || (!std::isfinite(in.dof) && !std::isfinite(dof0)))) {
        return MakeError(budget.file, 0,
                         "input '" + in.name +
                             "' is correlated with inputs of other degrees of freedom: the "
                             "joint t distribution needs one common dof");
      }
    }
    const Eigen::Index m = static_cast<Eigen::Index>(members.size());
    Eigen::MatrixXd corr(m, m);
    for (Eigen::Index i = 0; i < m; ++i) {
      for (Eigen::Index j = 0; j < m; ++j) {
        corr(i, j) =
            i == j ? 1.0 : r[members[static_cast<size_t>(i)]][members[static_cast<size_t>(j)]];
      }
    }
    Eigen::LLT<Eigen::MatrixXd> llt(corr);
    if (llt.info() != Eigen::Success) {
      return MakeError(budget.file, 0,
                       "the correlation matrix of input '" + budget.inputs[members[0]].name +
                           "' and the inputs correlated with it is not positive definite");
    }
    g.cholesky = llt.matrixL();
    g.dof = std::isfinite(dof0) ? dof0 : 0.0;
    if (g.dof > 0.0) g.gamma = GammaSampler(0.5 * g.dof);
    const int gi = static_cast<int>(plan.groups.size());
    for (size_t i : members) {
      plan.group_of[i] = gi;
      plan.inputs[i].kind = InputPlan::Kind::kGroupMember;
      plan.inputs[i].scale = budget.inputs[i].u;
    }
    plan.groups.push_back(std::move(g));
  }
  return plan;
}

// Fills columns[i][0..n) for every input, JCGM 101 6.4.
void SampleChunk(const Plan& plan, pcg64& rng, size_t n, std::vector<std::vector<double>>* cols) {
  boost::random::normal_distribution<double> normal;
  for (size_t i = 0; i < plan.inputs.size(); ++i) {
    const InputPlan& p = plan.inputs[i];
    double* x = (*cols)[i].data();
    switch (p.kind) {
      case InputPlan::Kind::kConstant:
        for (size_t k = 0; k < n; ++k) x[k] = p.value;
        break;
      case InputPlan::Kind::kNormal:  // 6.4.7.4
        for (size_t k = 0; k < n; ++k) x[k] = p.value + p.scale * normal(rng);
        break;
      case InputPlan::Kind::kT: {  // 6.4.9.5: x + s t_nu, t_nu = z / sqrt(chi2_nu / nu)
        const double half_dof = 0.5 * p.dof;
        for (size_t k = 0; k < n; ++k) {
          const double z = normal(rng);
          const double g = p.gamma(rng, normal);  // chi2_nu / 2
          x[k] = p.value + p.scale * z * std::sqrt(half_dof / g);
        }
        break;
      }
      case InputPlan::Kind::kRectangular: {  // 6.4.2.4: a + (b - a) r
        const double lo = p.value - p.a;
        const double width = 2.0 * p.a;
        for (size_t k = 0; k < n; ++k) x[k] = lo + width * Uniform(rng);
        break;
      }
      case InputPlan::Kind::kTriangular: {  // 6.4.5.4: a + (b - a)(r1 + r2)/2
        const double lo = p.value - p.a;
        for (size_t k = 0; k < n; ++k) x[k] = lo + p.a * (Uniform(rng) + Uniform(rng));
        break;
      }
      case InputPlan::Kind::kArcsine: {
        // 6.4.6.4 draws (a + b)/2 + (b - a)/2 sin(2 pi r). Same law, no sine: for a point
        // uniform in the unit disc, cos(2 phi) = (s^2 - t^2)/(s^2 + t^2) with phi uniform.
        for (size_t k = 0; k < n; ++k) {
          double s, t, w;
          do {
            s = 2.0 * Uniform(rng) - 1.0;
            t = 2.0 * Uniform(rng) - 1.0;
            w = s * s + t * t;
          } while (w > 1.0 || w == 0.0);
          x[k] = p.value + p.a * (s * s - t * t) / w;
        }
        break;
      }
      case InputPlan::Kind::kTrapezoidal: {  // 6.4.4.4: a + (b-a)/2 [(1+beta) r1 + (1-beta) r2]
        const double lo = p.value - p.a;
        for (size_t k = 0; k < n; ++k) {
          const double r1 = Uniform(rng);
          const double r2 = Uniform(rng);
          x[k] = lo + p.a * ((1.0 + p.beta) * r1 + (1.0 - p.beta) * r2);
        }
        break;
      }
      case InputPlan::Kind::kCtrap: {
        // 6.4.3.4: a_s = (a - d) + 2 d r1, b_s = (a + b) - a_s, x = a_s + (b_s - a_s) r2.
        const double lo = p.value - p.a;
        const double hi = p.value + p.a;
        for (size_t k = 0; k < n; ++k) {
          const double as = (lo - p.d) + 2.0 * p.d * Uniform(rng);
          const double bs = (lo + hi) - as;
          x[k] = as + (bs - as) * Uniform(rng);
        }
        break;
      }
      case InputPlan::Kind::kGroupMember: {
        const GroupPlan& g = plan.groups[static_cast<size_t>(plan.group_of[i])];
        if (g.members.front() != i) break;  // Drawn with its group's first member.
        // 6.4.8.4: x = mu + diag(u) L z; with common finite dof, divided by sqrt(chi2/nu).
        const size_t m = g.members.size();
        std::vector<double> z(m);
        for (size_t k = 0; k < n; ++k) {
          for (size_t j = 0; j < m; ++j) z[j] = normal(rng);
          const double shrink = g.dof > 0.0 ? std::sqrt(0.5 * g.dof / g.gamma(rng, normal)) : 1.0;
          for (size_t j = 0; j < m; ++j) {
            double v = 0.0;
            for (size_t l = 0; l <= j; ++l) {
              v += g.cholesky(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(l)) * z[l];
            }
            const InputPlan& q = plan.inputs[g.members[j]];
            (*cols)[g.members[j]][k] = q.value + q.scale * v * shrink;
          }
        }
        break;
      }
    }
  }
}

struct NanReport {
  int64_t trial = -1;
  std::vector<double> inputs;
  int64_t count = 0;
};

// Simulates trials [first, first + count) into out; first is a multiple of kChunkTrials.
NanReport Simulate(const Plan& plan, int64_t first, int64_t count, double* out, int threads) {
  const int64_t first_chunk = first / kChunkTrials;
  const int64_t chunks = (count + kChunkTrials - 1) / kChunkTrials;
  const int workers = static_cast<int>(std::max<int64_t>(1, std::min<int64_t>(threads, chunks)));
  std::vector<NanReport> reports(static_cast<size_t>(workers));
  const auto work = [&](int w) {
    auto evaluator = plan.model->MakeEvaluator();
    const size_t n_in = plan.inputs.size();
    std::vector<std::vector<double>> cols(n_in, std::vector<double>(kChunkTrials));
    std::vector<const double*> ptrs(n_in);
    for (size_t i = 0; i < n_in; ++i) ptrs[i] = cols[i].data();
    NanReport& report = reports[static_cast<size_t>(w)];
    // Contiguous share of the chunks for each worker.
    const int64_t begin = chunks * w / workers;
    const int64_t end = chunks * (w + 1) / workers;
    for (int64_t c = begin; c < end; ++c) {
      const int64_t global = first_chunk + c;
      pcg64 rng(SplitMix64(plan.seed + static_cast<uint64_t>(global)),
                static_cast<uint64_t>(global));
      const int64_t offset = c * kChunkTrials;
      const size_t n = static_cast<size_t>(std::min<int64_t>(kChunkTrials, count - offset));
      SampleChunk(plan, rng, n, &cols);
      double* y = out + offset;
      evaluator->EvaluateBlock(ptrs.data(), n, y);
      for (size_t k = 0; k < n; ++k) {
        if (!std::isfinite(y[k])) {
          if (report.count == 0) {
            report.trial = first + offset + static_cast<int64_t>(k);
            for (size_t i = 0; i < n_in; ++i) report.inputs.push_back(cols[i][k]);
          }
          ++report.count;
        }
      }
    }
  };
  if (workers == 1) {
    work(0);
  } else {
    std::vector<std::thread> pool;
    for (int w = 0; w < workers; ++w) pool.emplace_back(work, w);
    for (auto& t : pool) t.join();
  }
  NanReport total;
  for (const auto& r : reports) {
    if (r.count > 0 && (total.count == 0 || r.trial < total.trial)) {
      total.trial = r.trial;
      total.inputs = r.inputs;
    }
    total.count += r.count;
  }
  return total;
}

struct Moments {
  double mean = 0.0;
  double u = 0.0;
};

// JCGM 101 7.6 (two passes).
Moments MeanAndU(const double* y, size_t m) {
  double sum = 0.0;
  for (size_t k = 0; k < m; ++k) sum += y[k];
  Moments r;
  r.mean = sum / static_cast<double>(m);
  double ss = 0.0;
  for (size_t k = 0; k < m; ++k) ss += (y[k] - r.mean) * (y[k] - r.mean);
  r.u = m > 1 ? std::sqrt(ss / static_cast<double>(m - 1)) : 0.0;
  return r;
}

struct Intervals {
  CoverageInterval symmetric;
  CoverageInterval shortest;
};

// JCGM 101 7.7 by partial selection: only the L = M - q lowest and highest order
// statistics are put in order.
Intervals CoverageIntervals(double* v, size_t m, double p) {
  METRO_CHECK(m >= 2 && p > 0.0 && p < 1.0);
  const double pm = p * static_cast<double>(m);
  size_t q = pm == std::floor(pm) ? static_cast<size_t>(pm) : static_cast<size_t>(pm + 0.5);
  q = std::min(std::max<size_t>(q, 1), m - 1);
  const size_t tail = m - q;  // L
  if (2 * tail >= m) {
    std::sort(v, v + m);
  } else {
    std::nth_element(v, v + tail, v + m);
    std::sort(v, v + tail);
    std::nth_element(v + tail, v + q, v + m);
    std::sort(v + q, v + m);
  }
  Intervals out;
  // 1-based r; y_(r) = v[r - 1].
  const size_t r = (tail % 2 == 0) ? tail / 2 : (tail + 1) / 2;
  out.symmetric = {v[r - 1], v[r + q - 1]};
  size_t best = 1;
  double width = v[q] - v[0];
  for (size_t s = 2; s <= tail; ++s) {
    const double w = v[s + q - 1] - v[s - 1];
    if (w < width) {
      width = w;
      best = s;
    }
  }
  out.shortest = {v[best - 1], v[best + q - 1]};
  return out;
}

Error NanError(const Budget& budget, const NanReport& nan, int64_t trials) {
  std::string at;
  for (size_t i = 0; i < budget.inputs.size() && i < nan.inputs.size(); ++i) {
    at += (i ? ", " : "") + budget.inputs[i].name + " = " + std::to_string(nan.inputs[i]);
  }
  return MakeError(budget.file, 0,
                   "model '" + (budget.model.empty() ? std::string("sum c_i x_i") : budget.model) +
                       "' is NaN or infinite in " + std::to_string(nan.count) + " of " +
                       std::to_string(trials) + " Monte Carlo trials (first at " + at +
                       "); restrict the input distributions to the model's domain");
}

}  // namespace

double NumericalTolerance(double u, int ndig) {
  if (!(u > 0.0) || !std::isfinite(u)) return std::numeric_limits<double>::quiet_NaN();
  // JCGM 101 7.9.2: u = c 10^l, c with ndig digits; round first (0.0996 -> 10 x 10^-2).
  int l = static_cast<int>(std::floor(std::log10(u))) - (ndig - 1);
  const double c = std::round(u / std::pow(10.0, l));
  if (c >= std::pow(10.0, ndig)) ++l;
  return 0.5 * std::pow(10.0, l);
}

CoverageInterval SymmetricInterval(std::vector<double>* values, double coverage) {
  return CoverageIntervals(values->data(), values->size(), coverage).symmetric;
}

CoverageInterval ShortestInterval(std::vector<double>* values, double coverage) {
  return CoverageIntervals(values->data(), values->size(), coverage).shortest;
}

GufValidation ValidateGuf(const GumResult& gum, const McResult& mc, int ndig) {
  GufValidation v;
  v.delta = NumericalTolerance(gum.u > 0.0 ? gum.u : mc.u, ndig);
  v.d_low = std::fabs(gum.value - gum.expanded - mc.shortest.low);
  v.d_high = std::fabs(gum.value + gum.expanded - mc.shortest.high);
  v.validated = std::isfinite(v.delta) && v.d_low <= v.delta && v.d_high <= v.delta;
  return v;
}

Result<McResult> RunMonteCarlo(const Budget& budget) {
  return RunMonteCarlo(budget, budget.monte_carlo);
}

Result<McResult> RunMonteCarlo(const Budget& budget, const McOptions& options, bool keep_samples) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(budget.file, 0, "monte_carlo: " + why);
  std::vector<std::string> names;
  std::vector<double> c;
  for (const auto& in : budget.inputs) {
    names.push_back(in.name);
    c.push_back(in.sensitivity.value_or(0.0));
  }
  Result<internal::MeasurementModel> parsed =
      budget.model.empty()
          ? Result<internal::MeasurementModel>(internal::MeasurementModel::Linear(c))
          : internal::MeasurementModel::FromExpression(budget.model, names);
  if (!parsed.ok()) return MakeError(budget.file, 0, parsed.error().message);
  auto plan_result = MakePlan(budget);
  if (!plan_result.ok()) return plan_result.error();
  Plan plan = std::move(plan_result).value();
  plan.model = &parsed.value();
  plan.seed = options.seed;

  McResult result;
  result.adaptive = options.adaptive;
  result.seed = options.seed;
  result.coverage = options.coverage;
  result.threads = options.threads > 0
                       ? options.threads
                       : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  result.generator =
      "pcg64 (pcg-cpp PCG XSL RR 128/64); chunk c of 1000 trials uses state "
      "splitmix64(seed + c) on stream c";
  std::vector<double> y;

  if (!options.adaptive) {
    y.resize(static_cast<size_t>(options.trials));
    const NanReport nan = Simulate(plan, 0, options.trials, y.data(), result.threads);
    if (nan.count > 0) return NanError(budget, nan, options.trials);
    result.trials = options.trials;
    result.blocks = 1;
    result.converged = true;
  } else {
    // JCGM 101 7.9 with the robust rule (docs/uncertainty.md).
    const double j = std::ceil(100.0 / (1.0 - options.coverage));
    int64_t block = std::max<int64_t>(static_cast<int64_t>(j), 10000);
    block = (block + kChunkTrials - 1) / kChunkTrials * kChunkTrials;
    std::vector<double> means, us, lows, highs;
    std::vector<double> scratch(static_cast<size_t>(block));
    double pooled_sum = 0.0;
    double pooled_ss = 0.0;  // sum over blocks of (M_b - 1) u_h^2
    const int64_t min_blocks = 10;
    for (int64_t h = 1; h * block <= options.max_trials; ++h) {
      const int64_t first = (h - 1) * block;
      y.resize(static_cast<size_t>(h * block));
      const NanReport nan = Simulate(plan, first, block, y.data() + first, result.threads);
      if (nan.count > 0) return NanError(budget, nan, h * block);
      const Moments m = MeanAndU(y.data() + first, static_cast<size_t>(block));
      std::copy(y.begin() + first, y.begin() + first + block, scratch.begin());
      const Intervals iv = CoverageIntervals(scratch.data(), scratch.size(), options.coverage);
      means.push_back(m.mean);
      us.push_back(m.u);
      lows.push_back(iv.symmetric.low);
      highs.push_back(iv.symmetric.high);
      pooled_sum += m.mean * static_cast<double>(block);
      pooled_ss += m.u * m.u * static_cast<double>(block - 1);
      result.trials = h * block;
      result.blocks = h;
      if (h < min_blocks) continue;
      // Pooled u(y) from the h blocks: within-block and between-block sums of squares.
      const double total = static_cast<double>(h * block);
      const double grand = pooled_sum / total;
      double between = 0.0;
      for (double mean : means) between += (mean - grand) * (mean - grand);
      const double u_pooled =
          std::sqrt((pooled_ss + static_cast<double>(block) * between) / (total - 1.0));
      const double delta = NumericalTolerance(u_pooled, options.ndig);
      const double t =
          boost::math::quantile(boost::math::students_t(static_cast<double>(h - 1)), 0.975);
      const auto settled = [&](const std::vector<double>& z) {
        const Moments s = MeanAndU(z.data(), z.size());
        return t * s.u / std::sqrt(static_cast<double>(z.size())) <= delta;
      };
      if (settled(means) && settled(us) && settled(lows) && settled(highs)) {
        result.converged = true;
        break;
      }
    }
    if (!result.converged) {
      result.message = "adaptive procedure did not settle within max_trials = " +
                       std::to_string(options.max_trials) + " trials";
    }
  }
  const Moments m = MeanAndU(y.data(), y.size());
  result.value = m.mean;
  result.u = m.u;
  result.delta = NumericalTolerance(m.u, options.ndig);
  if (keep_samples) {
    std::vector<double> copy = y;
    const Intervals iv = CoverageIntervals(copy.data(), copy.size(), options.coverage);
    result.symmetric = iv.symmetric;
    result.shortest = iv.shortest;
    result.samples = std::move(y);
  } else {
    const Intervals iv = CoverageIntervals(y.data(), y.size(), options.coverage);
    result.symmetric = iv.symmetric;
    result.shortest = iv.shortest;
  }
  result.ok = result.converged;
  return result;
}

}  // namespace metro
