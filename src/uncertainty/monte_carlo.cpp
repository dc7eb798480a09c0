// RunMonteCarlo runs these stages, in this order (JCGM 101:2008; docs/uncertainty.md):
//
//   plan       MakePlan, StartResult,          the model and the draws; what is undefined
//              ToleranceScaleFor               (6.4.9.4); delta's scale
//   fixed      RunFixed                        M trials at once: moments, intervals, delta
//   adaptive   RunAdaptive: AddBlock,          7.9: blocks until stage 1 (block statistics)
//              StableBlocks, StableShortest    and stage 2 (shortest end points) are within
//                                              delta
//              FinishAdaptive                  the reported numbers from all the trials
#include "metro/uncertainty/monte_carlo.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <atomic>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <boost/random/normal_distribution.hpp>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <pcg_random.hpp>

#include "core/parallel.hpp"
#include "metro/core/cancel.hpp"
#include "uncertainty/mc_sampling.hpp"
#include "uncertainty/model.hpp"
#include "uncertainty/model_quote.hpp"

namespace metro {
namespace {

using internal::WordSource;

// Uniform on (0, 1).
inline double UniformOpen(WordSource& rng) {
  return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
}

// Gamma(alpha, 1), Marsaglia and Tsang, ACM TOMS 26 (2000) 363-372; alpha < 1 through
// Gamma(alpha + 1) U^(1/alpha).
struct GammaSampler {
  explicit GammaSampler(double alpha_in = 1.0)
      : alpha(alpha_in), d((alpha_in < 1.0 ? alpha_in + 1.0 : alpha_in) - 1.0 / 3.0) {
    c = 1.0 / std::sqrt(9.0 * d);
  }
  double operator()(WordSource& rng, boost::random::normal_distribution<double>& normal) const {
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
void SampleChunk(const Plan& plan, WordSource& rng, size_t n, internal::SamplerScratch* scratch,
                 std::vector<std::vector<double>>* cols) {
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
      case InputPlan::Kind::kT:  // 6.4.9.5: x + s t_nu (Bailey's polar method)
        internal::StudentTBlock(rng, p.dof, p.value, p.scale, n, scratch, x);
        break;
      case InputPlan::Kind::kRectangular: {  // 6.4.2.4: a + (b - a) r
        const double lo = p.value - p.a;
        const double width = 2.0 * p.a;
        internal::UniformBlock(rng, n, x);
        for (size_t k = 0; k < n; ++k) x[k] = lo + width * x[k];
        break;
      }
      case InputPlan::Kind::kTriangular: {  // 6.4.5.4: a + (b - a)(r1 + r2)/2
        const double lo = p.value - p.a;
        const double* r1 = scratch->a();
        const double* r2 = scratch->b();
        internal::UniformBlock(rng, n, scratch->a());
        internal::UniformBlock(rng, n, scratch->b());
        for (size_t k = 0; k < n; ++k) x[k] = lo + p.a * (r1[k] + r2[k]);
        break;
      }
      case InputPlan::Kind::kArcsine:
        // 6.4.6.4 draws (a + b)/2 + (b - a)/2 sin(2 pi r). Same law, no sine: for a point
        // uniform in the unit disc, cos(2 phi) = (s^2 - t^2)/(s^2 + t^2) with phi uniform.
        internal::ArcsineBlock(rng, p.value, p.a, n, scratch, x);
        break;
      case InputPlan::Kind::kTrapezoidal: {  // 6.4.4.4: a + (b-a)/2 [(1+beta) r1 + (1-beta) r2]
        const double lo = p.value - p.a;
        const double w1 = p.a * (1.0 + p.beta);
        const double w2 = p.a * (1.0 - p.beta);
        const double* r1 = scratch->a();
        const double* r2 = scratch->b();
        internal::UniformBlock(rng, n, scratch->a());
        internal::UniformBlock(rng, n, scratch->b());
        for (size_t k = 0; k < n; ++k) x[k] = lo + (w1 * r1[k] + w2 * r2[k]);
        break;
      }
      case InputPlan::Kind::kCtrap: {
        // 6.4.3.4: a_s = (a - d) + 2 d r1, b_s = (a + b) - a_s, x = a_s + (b_s - a_s) r2.
        const double lo = p.value - p.a;
        const double hi = p.value + p.a;
        const double a_s0 = lo - p.d;
        const double two_d = 2.0 * p.d;
        const double a_plus_b = lo + hi;
        const double* r1 = scratch->a();
        const double* r2 = scratch->b();
        internal::UniformBlock(rng, n, scratch->a());
        internal::UniformBlock(rng, n, scratch->b());
        for (size_t k = 0; k < n; ++k) {
          const double as = a_s0 + two_d * r1[k];
          const double bs = a_plus_b - as;
          x[k] = as + (bs - as) * r2[k];
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

struct Moments {
  double mean = 0.0;
  double u = 0.0;
};

// Mean and sum of squared deviations of one chunk, combined over chunks in chunk order.
struct ChunkMoments {
  double n = 0.0;
  double mean = 0.0;
  double m2 = 0.0;
};

// JCGM 101 7.6 over all chunks: each chunk by two passes, chunks merged in order by the
// pairwise update of Chan, Golub and LeVeque (1979):
//   n = n_a + n_b, delta = mean_b - mean_a, mean = mean_a + delta n_b / n,
//   m2 = m2_a + m2_b + delta^2 n_a n_b / n.
// The order is fixed, so the result does not depend on the thread count.
Moments MergeChunkMoments(const std::vector<ChunkMoments>& chunks) {
  ChunkMoments total;
  for (const ChunkMoments& c : chunks) {
    const double n = total.n + c.n;
    const double delta = c.mean - total.mean;
    total.mean += delta * c.n / n;
    total.m2 += c.m2 + delta * delta * total.n * c.n / n;
    total.n = n;
  }
  Moments r;
  r.mean = total.mean;
  r.u = total.n > 1.0 ? std::sqrt(total.m2 / (total.n - 1.0)) : 0.0;
  return r;
}

// Simulates trials [first, first + count) into out; first is a multiple of kChunkTrials.
// chunk_moments (optional) receives one entry per chunk.
// on_trials_done (may be empty) hears of the trials done, every kProgressChunks chunks.
constexpr int64_t kProgressChunks = 64;

NanReport Simulate(const Plan& plan, int64_t first, int64_t count, double* out, int threads,
                   const std::function<void(int64_t)>& on_trials_done,
                   std::vector<ChunkMoments>* chunk_moments = nullptr) {
  const int64_t first_chunk = first / kChunkTrials;
  const int64_t chunks = (count + kChunkTrials - 1) / kChunkTrials;
  if (chunk_moments != nullptr) chunk_moments->assign(static_cast<size_t>(chunks), {});
  const int workers = static_cast<int>(std::max<int64_t>(1, std::min<int64_t>(threads, chunks)));
  std::vector<NanReport> reports(static_cast<size_t>(workers));
  std::atomic<bool> stop{false};
  const auto work = [&](int w) {
    auto evaluator = plan.model->MakeEvaluator();
    const size_t n_in = plan.inputs.size();
    std::vector<std::vector<double>> cols(n_in, std::vector<double>(kChunkTrials));
    internal::SamplerScratch scratch(kChunkTrials);
    std::vector<const double*> ptrs(n_in);
    for (size_t i = 0; i < n_in; ++i) ptrs[i] = cols[i].data();
    NanReport& report = reports[static_cast<size_t>(w)];
    // Contiguous share of the chunks for each worker.
    const int64_t begin = chunks * w / workers;
    const int64_t end = chunks * (w + 1) / workers;
    int64_t unreported = 0;
    for (int64_t c = begin; c < end && !stop.load(std::memory_order_relaxed); ++c) {
      ThrowIfCancelled();  // The caller's Ctrl-C (metro/core/cancel.hpp), between chunks.
      const int64_t global = first_chunk + c;
      WordSource rng(plan.seed, static_cast<uint64_t>(global));
      const int64_t offset = c * kChunkTrials;
      const size_t n = static_cast<size_t>(std::min<int64_t>(kChunkTrials, count - offset));
      SampleChunk(plan, rng, n, &scratch, &cols);
      double* y = out + offset;
      evaluator->EvaluateBlock(ptrs.data(), n, y);
      double sum = 0.0;
      for (size_t k = 0; k < n; ++k) sum += y[k];
      if (!std::isfinite(sum)) {
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
      if (chunk_moments != nullptr && report.count == 0) {
        ChunkMoments& cm = (*chunk_moments)[static_cast<size_t>(c)];
        cm.n = static_cast<double>(n);
        cm.mean = sum / cm.n;
        double m2 = 0.0;
        for (size_t k = 0; k < n; ++k) m2 += (y[k] - cm.mean) * (y[k] - cm.mean);
        cm.m2 = m2;
      }
      unreported += static_cast<int64_t>(n);
      if (on_trials_done && ((c - begin + 1) % kProgressChunks == 0 || c + 1 == end)) {
        on_trials_done(unreported);
        unreported = 0;
      }
    }
  };
  // core/parallel: an exception in a worker (std::bad_alloc, or one thrown by
  // on_trials_done) stops the other workers at their next chunk and reaches the caller.
  std::atomic<int> next_worker{0};
  internal::RunOnThreads(
      static_cast<size_t>(workers),
      [&] {
        for (int w = next_worker.fetch_add(1); w < workers; w = next_worker.fetch_add(1)) work(w);
      },
      [&] {
        next_worker.store(workers);
        stop.store(true);
      });
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

// JCGM 101 7.6, by the corrected two-pass algorithm (Chan, Golub & LeVeque 1983): the first
// mean's rounding (a sum of 1e5 values near 6.3e7 loses about 1e-4, 20 u for y = 2 pi f at
// 1e7 +- 1e-6 Hz, issue #36) is corrected by the mean residual of the second pass.
Moments MeanAndU(const double* y, size_t m) {
  double sum = 0.0;
  for (size_t k = 0; k < m; ++k) sum += y[k];
  const double dm = static_cast<double>(m);
  const double first = sum / dm;
  double s1 = 0.0, ss = 0.0;
  for (size_t k = 0; k < m; ++k) {
    const double e = y[k] - first;
    s1 += e;
    ss += e * e;
  }
  Moments r;
  r.mean = first + s1 / dm;
  r.u = m > 1 ? std::sqrt(std::max(0.0, ss - s1 * s1 / dm) / (dm - 1.0)) : 0.0;
  return r;
}

struct Intervals {
  CoverageInterval symmetric;
  CoverageInterval shortest;           // located by the fitted width minimum (below)
  CoverageInterval shortest_discrete;  // JCGM 101 7.7 as written
};

// Half-width, in probability, of the window over which the width function of the shortest
// interval is fitted (docs/uncertainty.md, "Shortest interval"): (1 - p)/5 up to M = 10^6
// trials, then shrinking like M^(-1/5) so that the fit's bias vanishes as M grows.
double FitWindow(double p, size_t m) {
  const double shrink = std::min(1.0, std::pow(1e6 / static_cast<double>(m), 0.2));
  return (1.0 - p) / 5.0 * shrink;
}

// Runs fn(lo, hi, slice) on `threads` contiguous slices of [0, n), through core/parallel
// (an exception in a slice reaches the caller).
template <typename Fn>
void ForEachSlice(int threads, size_t n, Fn fn) {
  const size_t slices = static_cast<size_t>(std::max(1, threads));
  internal::ParallelFor(slices, threads, [&](size_t t) {
    fn(n * t / slices, n * (t + 1) / slices, static_cast<int>(t));
  });
}

// The `tail` lowest values of v[0, m) in increasing order into *low and the `tail` highest
// into *high, without reordering v. Thresholds come from a pilot of kPilotRun consecutive
// values every kPilotStride values (few cache lines, spread over the whole sample): the
// pilot order statistic of rank P f + 4 sqrt(P f) + 16 (f = tail / m, P pilot values) lies
// above the tail-th lowest value unless the pilot is far from representative; every value
// strictly beyond the thresholds is then copied (about 1.15 tail values each side at
// M = 1e7, p = 0.99) and only those are put in order, the low and the high side on two
// threads. Returns false (nothing usable) when fewer than `tail` values lie beyond a
// threshold, e.g. with many ties or a periodic input; the caller then selects on the whole
// sample.
bool TailsByThreshold(const double* v, size_t m, size_t tail, int threads, std::vector<double>* low,
                      std::vector<double>* high) {
  constexpr size_t kPilotRun = 8;
  constexpr size_t kPilotStride = 1024;
  std::vector<double> pilot;
  pilot.reserve(m / kPilotStride * kPilotRun + kPilotRun);
  for (size_t k = 0; k + kPilotRun <= m; k += kPilotStride) {
    pilot.insert(pilot.end(), v + k, v + k + kPilotRun);
  }
  const size_t pilot_size = pilot.size();
  const double pf =
      static_cast<double>(pilot_size) * static_cast<double>(tail) / static_cast<double>(m);
  const size_t rank =
      std::min(pilot_size / 2 - 1, static_cast<size_t>(std::ceil(pf + 4.0 * std::sqrt(pf) + 16.0)));
  std::nth_element(pilot.begin(), pilot.begin() + static_cast<std::ptrdiff_t>(rank), pilot.end());
  const double low_threshold = pilot[rank];
  const size_t high_rank = pilot_size - 1 - rank;
  std::nth_element(pilot.begin(), pilot.begin() + static_cast<std::ptrdiff_t>(high_rank),
                   pilot.end());
  const double high_threshold = pilot[high_rank];
  const int workers = std::max(1, threads);
  std::vector<std::vector<double>> lows(static_cast<size_t>(workers));
  std::vector<std::vector<double>> highs(static_cast<size_t>(workers));
  ForEachSlice(workers, m, [&](size_t lo, size_t hi, int w) {
    std::vector<double>& l = lows[static_cast<size_t>(w)];
    std::vector<double>& h = highs[static_cast<size_t>(w)];
    const size_t expect = (hi - lo) * tail / m * 9 / 8 + 64;
    l.reserve(expect);
    h.reserve(expect);
    for (size_t k = lo; k < hi; ++k) {
      const double x = v[k];
      if (x < low_threshold) l.push_back(x);
      if (x > high_threshold) h.push_back(x);
    }
  });
  const auto gather = [](std::vector<std::vector<double>>* parts, std::vector<double>* out) {
    size_t total = 0;
    for (const auto& part : *parts) total += part.size();
    out->clear();
    out->reserve(total);
    for (const auto& part : *parts) out->insert(out->end(), part.begin(), part.end());
  };
  gather(&lows, low);
  gather(&highs, high);
  if (low->size() < tail || high->size() < tail) return false;
  const auto order_low = [&] {
    std::nth_element(low->begin(), low->begin() + static_cast<std::ptrdiff_t>(tail - 1),
                     low->end());
    low->resize(tail);
    std::sort(low->begin(), low->end());
  };
  const auto order_high = [&] {
    const auto cut = high->end() - static_cast<std::ptrdiff_t>(tail);
    std::nth_element(high->begin(), cut, high->end());
    high->erase(high->begin(), cut);
    std::sort(high->begin(), high->end());
  };
  if (threads > 1) {
    internal::RunBeside(order_high, order_low);  // core/parallel: exceptions reach the caller
  } else {
    order_low();
    order_high();
  }
  return true;
}

// JCGM 101 7.7 by partial selection: only the L = M - q lowest and highest order
// statistics are put in order. Large samples with L <= M/8 take them by threshold
// (TailsByThreshold, on `threads` threads) and leave v as it is; otherwise v is reordered.
Intervals CoverageIntervals(double* v, size_t m, double p, int threads = 1) {
  METRO_CHECK(m >= 2 && p > 0.0 && p < 1.0);
  const double pm = p * static_cast<double>(m);
  size_t q = pm == std::floor(pm) ? static_cast<size_t>(pm) : static_cast<size_t>(pm + 0.5);
  q = std::min(std::max<size_t>(q, 1), m - 1);
  const size_t tail = m - q;  // L
  std::vector<double> low, high;
  const bool by_threshold =
      m >= (size_t{1} << 18) && 8 * tail <= m && TailsByThreshold(v, m, tail, threads, &low, &high);
  if (!by_threshold) {
    if (2 * tail >= m) {
      std::sort(v, v + m);
    } else {
      std::nth_element(v, v + tail, v + m);
      std::sort(v, v + tail);
      std::nth_element(v + tail, v + q, v + m);
      std::sort(v + q, v + m);
    }
  }
  // y_(i + 1) = order statistic i (0-based); only i < L and i >= q are asked for.
  const auto y = [&](size_t i) {
    if (!by_threshold) return v[i];
    return i < tail ? low[i] : high[i - q];
  };
  Intervals out;
  // 1-based r; y_(r) = y(r - 1).
  const size_t r = (tail % 2 == 0) ? tail / 2 : (tail + 1) / 2;
  out.symmetric = {y(r - 1), y(r + q - 1)};
  size_t best = 1;
  double width = y(q) - y(0);
  for (size_t s = 2; s <= tail; ++s) {
    const double w = y(s + q - 1) - y(s - 1);
    if (w < width) {
      width = w;
      best = s;
    }
  }
  out.shortest_discrete = {y(best - 1), y(best + q - 1)};
  out.shortest = out.shortest_discrete;
  // The discrete minimiser `best` wanders on the noise of the widths: near the minimum the
  // width w(s) = y_(s+q) - y_(s) is flat to first order, so its argmin converges like
  // M^(-1/3) (Chernoff's rate for the argmin of a quadratic plus a Brownian motion), not
  // M^(-1/2). A least-squares parabola w(s) ~ c0 + c1 t + c2 t^2, t = (s - best)/W, over
  // the W ranks either side of `best` averages that noise; its vertex s* = best - W c1/(2 c2)
  // locates the minimum, and the end points are the order statistics at s* and s* + q,
  // interpolated linearly between ranks (the continuous G of JCGM 101 7.5.2). A minimum at
  // the edge (best = 1 or L), a window of fewer than 5 ranks, a fit without positive
  // curvature or a vertex outside the window keep the discrete interval.
  // The window also stays within a quarter of the distance from `best` to either edge of
  // [1, L]: near an edge the width is far from a parabola (the bias of the fitted vertex
  // grows like W^2 times the width's third derivative, which is large there).
  const size_t edge = std::min(best - 1, tail - best) / 4;
  const size_t window =
      std::min(edge, static_cast<size_t>(std::llround(FitWindow(p, m) * static_cast<double>(m))));
  if (best > 1 && best < tail && window >= 2) {
    const size_t lo = best > window ? best - window : 1;
    const size_t hi = std::min(tail, best + window);
    if (hi - lo + 1 >= 5) {
      const double w0 = y(best + q - 1) - y(best - 1);
      const double scale = static_cast<double>(window);
      double s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0, b0 = 0, b1 = 0, b2 = 0;
      for (size_t k = lo; k <= hi; ++k) {
        const double t = (static_cast<double>(k) - static_cast<double>(best)) / scale;
        const double w = (y(k + q - 1) - y(k - 1)) - w0;
        const double t2 = t * t;
        s0 += 1;
        s1 += t;
        s2 += t2;
        s3 += t2 * t;
        s4 += t2 * t2;
        b0 += w;
        b1 += t * w;
        b2 += t2 * w;
      }
      Eigen::Matrix3d a;
      a << s0, s1, s2, s1, s2, s3, s2, s3, s4;
      const Eigen::Vector3d c = a.ldlt().solve(Eigen::Vector3d(b0, b1, b2));
      const double t_min = (static_cast<double>(lo) - static_cast<double>(best)) / scale;
      const double t_max = (static_cast<double>(hi) - static_cast<double>(best)) / scale;
      if (c(2) > 0.0 && std::isfinite(c(1))) {
        const double t_star = -c(1) / (2.0 * c(2));
        if (t_star >= t_min && t_star <= t_max) {
          const double rank = static_cast<double>(best) + t_star * scale;  // 1-based s*
          const size_t k = std::min(tail - 1, static_cast<size_t>(std::floor(rank)));
          const double f = rank - static_cast<double>(k);  // in [0, 1]
          // y_(s) at real s between ranks k and k + 1 (0-based k - 1 and k).
          const auto at = [&](size_t i) { return y(i) + f * (y(i + 1) - y(i)); };
          out.shortest = {at(k - 1), at(k + q - 1)};
        }
      }
    }
  }
  return out;
}

// The adaptive rule's constants (docs/uncertainty.md): at least 10 blocks, G = 10 groups
// for the test of the shortest end points, which are taken to converge like M^(-2/5).
constexpr int64_t kMinBlocks = 10;
constexpr int64_t kGroups = 10;
constexpr double kShortestRate = 0.4;

struct GroupSpread {
  double s_low = 0.0;   // standard deviation of the G groups' shortest lower end points
  double s_high = 0.0;  // and of their upper end points
};

// y[0, m) split into kGroups consecutive groups of m / kGroups values; each group's shortest
// interval (copied, y is left as it is), groups on `threads` threads (core/parallel).
GroupSpread ShortestSpread(const double* y, size_t m, double p, int threads) {
  const size_t n = m / static_cast<size_t>(kGroups);
  std::vector<double> low(static_cast<size_t>(kGroups)), high(static_cast<size_t>(kGroups));
  internal::ParallelFor(static_cast<size_t>(kGroups), threads, [&](size_t g) {
    std::vector<double> copy(y + g * n, y + (g + 1) * n);
    const Intervals iv = CoverageIntervals(copy.data(), copy.size(), p);
    low[g] = iv.shortest.low;
    high[g] = iv.shortest.high;
  });
  return {MeanAndU(low.data(), low.size()).u, MeanAndU(high.data(), high.size()).u};
}

Error NanError(const Budget& budget, const NanReport& nan, int64_t trials) {
  std::string at;
  for (size_t i = 0; i < budget.inputs.size() && i < nan.inputs.size(); ++i) {
    at += (i ? ", " : "") + budget.inputs[i].name + " = " + std::to_string(nan.inputs[i]);
  }
  const std::string what = "is NaN or infinite in " + std::to_string(nan.count) + " of " +
                           std::to_string(trials) + " Monte Carlo trials (first at " + at +
                           "); restrict the input distributions to the model's domain";
  if (budget.model.empty()) return MakeError(budget.file, 0, "model 'sum c_i x_i' " + what);
  return internal::ModelError(budget, what);
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
  return CoverageIntervals(values->data(), values->size(), coverage).shortest_discrete;
}

CoverageInterval ShortestIntervalFitted(std::vector<double>* values, double coverage) {
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

namespace {

// u(y) (and the mean) of a run whose inputs have none are not numbers: NaN, with the note.
void MarkUndefinedMoments(McResult* result) {
  if (result->u_defined) return;
  result->u = std::nan("");
  if (!result->mean_defined) result->value = std::nan("");
  std::string names;
  for (const std::string& n : result->inputs_without_variance) {
    names += (names.empty() ? "" : ", ") + n;
  }
  const std::string note = fmt::format(
      "u(y) is undefined{}: input{} {} {} drawn from a t distribution with nu <= 2, which has "
      "no variance (JCGM 101 6.4.9.4); the coverage intervals are reported, delta rests on "
      "the symmetric interval",
      result->mean_defined ? "" : " and so is the mean (nu <= 1)",
      result->inputs_without_variance.size() == 1 ? "" : "s", names,
      result->inputs_without_variance.size() == 1 ? "is" : "are");
  result->message = result->message.empty() ? note : result->message + "; " + note;
}

}  // namespace

std::vector<std::string> InputsWithoutVariance(const Budget& budget) {
  std::vector<std::string> out;
  for (const BudgetInput& in : budget.inputs) {
    const bool t_like = in.distribution == Distribution::kNormal ||
                        in.distribution == Distribution::kTypeA ||
                        in.distribution == Distribution::kStudentT;
    const double scale = in.distribution == Distribution::kStudentT ? in.scale : in.u;
    if (t_like && scale != 0.0 && std::isfinite(in.dof) && in.dof <= 2.0) {
      out.push_back(fmt::format("{} (nu = {:g})", in.name, in.dof));
    }
  }
  return out;
}

namespace {

// ---- start --------------------------------------------------------------------------------

// The result before any trial: what is undefined (JCGM 101 6.4.9.4) and how it is drawn.
McResult StartResult(const Budget& budget, const McOptions& options) {
  McResult result;
  // JCGM 101 6.4.9.4: t_nu has a variance for nu > 2, a mean for nu > 1. Named before any
  // trial is drawn; the intervals stay defined, u (and for nu <= 1 the mean) do not.
  result.inputs_without_variance = InputsWithoutVariance(budget);
  result.u_defined = result.inputs_without_variance.empty();
  for (const BudgetInput& in : budget.inputs) {
    const bool t_like = in.distribution == Distribution::kNormal ||
                        in.distribution == Distribution::kTypeA ||
                        in.distribution == Distribution::kStudentT;
    if (t_like && std::isfinite(in.dof) && in.dof <= 1.0 &&
        (in.distribution == Distribution::kStudentT ? in.scale : in.u) != 0.0) {
      result.mean_defined = false;
    }
  }
  result.adaptive = options.adaptive;
  result.seed = options.seed;
  result.coverage = options.coverage;
  result.threads = internal::ResolveThreads(options.threads);
  result.generator =
      "pcg64 (pcg-cpp PCG XSL RR 128/64) x 4 interleaved; chunk c of 1000 trials: engine j "
      "starts at splitmix64(splitmix64(seed) + 4c + j) on stream 4c + j";
  return result;
}

// The scale delta rests on when u(y) is undefined: the symmetric interval's half-width over
// the normal coverage factor for p (for a normal y this is u(y)).
struct ToleranceScale {
  bool u_defined = true;
  double z_p = 0.0;
  double operator()(double u, double low, double high) const {
    return u_defined ? u : (high - low) / (2.0 * z_p);
  }
};

ToleranceScale ToleranceScaleFor(const McResult& result, const McOptions& options) {
  return {result.u_defined,
          boost::math::quantile(boost::math::normal(), 0.5 * (1.0 + options.coverage))};
}

// ---- fixed number of trials ---------------------------------------------------------------

Status RunFixed(const Budget& budget, const Plan& plan, const McOptions& options, bool keep_samples,
                const ToleranceScale& tolerance_scale, McResult* out) {
  McResult& result = *out;
  // Left uninitialised: the workers write (and first touch) every value. No huge-page
  // advice: 10^7 trials measured 0.36 s without it and 0.43 s with it, back to back on
  // the project's VM (docs/benchmarks-history.md, "Huge pages").
  const size_t m = static_cast<size_t>(options.trials);
  std::unique_ptr<double[]> values(new double[m]);
  std::vector<ChunkMoments> chunk_moments;
  const NanReport nan = Simulate(plan, 0, options.trials, values.get(), result.threads,
                                 options.on_trials_done, &chunk_moments);
  if (nan.count > 0) return NanError(budget, nan, options.trials);
  result.trials = options.trials;
  result.blocks = 1;
  result.converged = true;
  const Moments moments = MergeChunkMoments(chunk_moments);
  result.value = moments.mean;
  result.u = moments.u;
  if (keep_samples) result.samples.assign(values.get(), values.get() + m);
  const Intervals iv = CoverageIntervals(values.get(), m, options.coverage, result.threads);
  result.symmetric = iv.symmetric;
  result.shortest = iv.shortest;
  result.shortest_discrete = iv.shortest_discrete;
  result.delta = NumericalTolerance(tolerance_scale(moments.u, iv.symmetric.low, iv.symmetric.high),
                                    options.ndig);
  MarkUndefinedMoments(&result);
  result.ok = true;
  return Status::Ok();
}

// ---- adaptive -----------------------------------------------------------------------------

// The block statistics of the adaptive procedure so far.
struct Blocks {
  std::vector<double> means, us, lows, highs;
  double pooled_sum = 0.0;
  double pooled_ss = 0.0;  // sum over blocks of (M_b - 1) u_h^2
};

// One block of `block` trials at y: its mean, u and symmetric end points (scratch: room for
// the block's values, which CoverageIntervals reorders).
void AddBlock(const double* y, int64_t block, const McOptions& options,
              std::vector<double>* scratch, Blocks* blocks) {
  const Moments m = MeanAndU(y, static_cast<size_t>(block));
  std::copy(y, y + block, scratch->begin());
  const Intervals iv = CoverageIntervals(scratch->data(), scratch->size(), options.coverage);
  blocks->means.push_back(m.mean);
  blocks->us.push_back(m.u);
  blocks->lows.push_back(iv.symmetric.low);
  blocks->highs.push_back(iv.symmetric.high);
  blocks->pooled_sum += m.mean * static_cast<double>(block);
  blocks->pooled_ss += m.u * m.u * static_cast<double>(block - 1);
}

// Stage 1 after h blocks: delta from the pooled u(y), and the 95 % half-widths of the
// block statistics (result->stability, ->delta). True when all are within delta.
bool StableBlocks(const Blocks& blocks, int64_t h, int64_t block, const McOptions& options,
                  const ToleranceScale& tolerance_scale, McResult* result) {
  const std::vector<double>& lows = blocks.lows;
  const std::vector<double>& highs = blocks.highs;
  // Pooled u(y) from the h blocks: within-block and between-block sums of squares.
  const double total = static_cast<double>(h * block);
  const double grand = blocks.pooled_sum / total;
  double between = 0.0;
  for (double mean : blocks.means) between += (mean - grand) * (mean - grand);
  const double u_pooled =
      std::sqrt((blocks.pooled_ss + static_cast<double>(block) * between) / (total - 1.0));
  const double delta =
      NumericalTolerance(tolerance_scale(u_pooled, MeanAndU(lows.data(), lows.size()).mean,
                                         MeanAndU(highs.data(), highs.size()).mean),
                         options.ndig);
  // Stage 1, JCGM 101 7.9.4 with t_0.975(h - 1) for its factor 2: the 95 % half-width
  // t s(z_1..z_h)/sqrt(h) of the pooled value of each block statistic that converges
  // like M^(-1/2) (mean, u, symmetric end points).
  const double t =
      boost::math::quantile(boost::math::students_t(static_cast<double>(h - 1)), 0.975);
  const auto half_width = [&](const std::vector<double>& z) {
    return t * MeanAndU(z.data(), z.size()).u / std::sqrt(static_cast<double>(z.size()));
  };
  McStability st;
  st.value = half_width(blocks.means);
  st.u = half_width(blocks.us);
  st.symmetric_low = half_width(lows);
  st.symmetric_high = half_width(highs);
  result->stability = st;
  result->delta = delta;
  // An undefined mean or u is not a reported number: its block spread never settles
  // and is not tested (McResult::inputs_without_variance).
  if (!result->mean_defined) st.value = std::nan("");
  if (!result->u_defined) st.u = std::nan("");
  result->stability = st;
  return !((result->mean_defined && st.value > delta) || (result->u_defined && st.u > delta) ||
           st.symmetric_low > delta || st.symmetric_high > delta);
}

// Stage 2, the shortest end points themselves: the pooled h blocks split into G = 10
// groups of h/G blocks, each group's shortest interval (as reported, fitted minimum);
// their spread s_G, scaled to the pooled M = G M_G by the slowest rate of that
// estimator (M^(-2/5), docs/uncertainty.md), gives the half-width
// t_0.975(G - 1) s_G G^(-2/5). Below delta: settled (true). Otherwise *next_group_test is
// where that rate predicts success (Stein's two-stage idea as applied to JCGM 101 by
// Wuebbeler, Harris, Cox and Elster, Metrologia 47 (2010) 317), at least 10 and at
// most h blocks further on, on a multiple of G blocks.
bool StableShortest(const std::vector<double>& y, int64_t h, int64_t block,
                    const McOptions& options, McResult* result, int64_t* next_group_test) {
  const double delta = result->delta;
  McStability st = result->stability;
  const GroupSpread g =
      ShortestSpread(y.data(), static_cast<size_t>(h * block), options.coverage, result->threads);
  const double t_g =
      boost::math::quantile(boost::math::students_t(static_cast<double>(kGroups - 1)), 0.975);
  const double reduce = std::pow(static_cast<double>(kGroups), -kShortestRate);
  st.shortest_low = t_g * g.s_low * reduce;
  st.shortest_high = t_g * g.s_high * reduce;
  st.groups = kGroups;
  result->stability = st;
  const double worst = std::max(st.shortest_low, st.shortest_high);
  if (worst <= delta) return true;
  const double predicted = static_cast<double>(h) * std::pow(worst / delta, 1.0 / kShortestRate);
  const int64_t want = static_cast<int64_t>(std::min(
      std::max(predicted, static_cast<double>(h + kGroups)), 2.0 * static_cast<double>(h)));
  *next_group_test = (want + kGroups - 1) / kGroups * kGroups;
  return false;
}

// JCGM 101 7.9, with the rule of docs/uncertainty.md ("Adaptive procedure"): stop only
// when every reported number is stable to delta (7.9.2), the shortest interval's end
// points tested on themselves. The trials drawn are left in *y.
Status RunAdaptive(const Budget& budget, const Plan& plan, const McOptions& options,
                   const ToleranceScale& tolerance_scale, McResult* result,
                   std::vector<double>* y) {
  const double j = std::ceil(100.0 / (1.0 - options.coverage));
  int64_t block = std::max<int64_t>(static_cast<int64_t>(j), 10000);
  block = (block + kChunkTrials - 1) / kChunkTrials * kChunkTrials;
  Blocks blocks;
  std::vector<double> scratch(static_cast<size_t>(block));
  int64_t next_group_test = kMinBlocks;  // h of the next test of the shortest end points
  for (int64_t h = 1; h * block <= options.max_trials; ++h) {
    const int64_t first = (h - 1) * block;
    y->resize(static_cast<size_t>(h * block));
    const NanReport nan =
        Simulate(plan, first, block, y->data() + first, result->threads, options.on_trials_done);
    if (nan.count > 0) return NanError(budget, nan, h * block);
    AddBlock(y->data() + first, block, options, &scratch, &blocks);
    result->trials = h * block;
    result->blocks = h;
    if (h < kMinBlocks) continue;
    if (!StableBlocks(blocks, h, block, options, tolerance_scale, result) || h < next_group_test ||
        h % kGroups != 0) {
      continue;
    }
    if (StableShortest(*y, h, block, options, result, &next_group_test)) {
      result->converged = true;
      break;
    }
  }
  if (!result->converged) {
    result->message = "adaptive procedure did not settle within max_trials = " +
                      std::to_string(options.max_trials) + " trials";
  }
  return Status::Ok();
}

// The adaptive run's reported numbers from all its trials y.
void FinishAdaptive(const McOptions& options, bool keep_samples,
                    const ToleranceScale& tolerance_scale, std::vector<double> y, McResult* out) {
  McResult& result = *out;
  const Moments m = MeanAndU(y.data(), y.size());
  result.value = m.mean;
  result.u = m.u;
  if (keep_samples) {
    std::vector<double> copy = y;
    const Intervals iv =
        CoverageIntervals(copy.data(), copy.size(), options.coverage, result.threads);
    result.symmetric = iv.symmetric;
    result.shortest = iv.shortest;
    result.shortest_discrete = iv.shortest_discrete;
    result.samples = std::move(y);
  } else {
    const Intervals iv = CoverageIntervals(y.data(), y.size(), options.coverage, result.threads);
    result.symmetric = iv.symmetric;
    result.shortest = iv.shortest;
    result.shortest_discrete = iv.shortest_discrete;
  }
  result.delta = NumericalTolerance(
      tolerance_scale(m.u, result.symmetric.low, result.symmetric.high), options.ndig);
  MarkUndefinedMoments(&result);
  result.ok = result.converged;
}

}  // namespace

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
  if (!parsed.ok()) return internal::ModelError(budget, parsed.error());
  auto plan_result = MakePlan(budget);
  if (!plan_result.ok()) return plan_result.error();
  Plan plan = std::move(plan_result).value();
  plan.model = &parsed.value();
  plan.seed = options.seed;

  McResult result = StartResult(budget, options);
  const ToleranceScale tolerance_scale = ToleranceScaleFor(result, options);
  if (!options.adaptive) {
    Status fixed = RunFixed(budget, plan, options, keep_samples, tolerance_scale, &result);
    if (!fixed.ok()) return fixed.error();
    return result;
  }
  std::vector<double> y;
  Status adaptive = RunAdaptive(budget, plan, options, tolerance_scale, &result, &y);
  if (!adaptive.ok()) return adaptive.error();
  FinishAdaptive(options, keep_samples, tolerance_scale, std::move(y), &result);
  return result;
}

}  // namespace metro
