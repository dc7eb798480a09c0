#include "metro/stats/spectral_mean.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "core/simd_clones.hpp"

namespace metro {
namespace {

// Values read per chunk by the chunked estimate: a whole number of kBlock lag-product blocks
// and of four-value lanes.
constexpr size_t kStreamChunk = size_t{1} << 16;

// Order cap: min(floor(10 log10 n), floor(n / 10)), at least 1.
int DefaultMaxOrder(size_t n) {
  const int by_log = static_cast<int>(std::floor(10.0 * std::log10(static_cast<double>(n))));
  const int by_length = static_cast<int>(n / 10);
  return std::max(1, std::min(by_log, by_length));
}

// 1' sigma_e^2 Gamma_p^-1 1 of the AR(p) model phi, by the Gohberg-Semencul formula
// sigma_e^2 Gamma_p^-1 = A A' - B B', A and B lower-triangular Toeplitz with first columns
// (1, -phi_1, ..., -phi_{p-1}) and (phi_p, phi_{p-1}, ..., phi_1):
//   1' A A' 1 = sum_j (sum_{m=0}^{p-1-j} a_m)^2,  1' B B' 1 = sum_j (sum_{m=0}^{p-1-j} b_m)^2.
double GohbergSemencul11(const std::vector<double>& phi) {
  const size_t p = phi.size();
  double a_sum = 0.0, b_sum = 0.0, aa = 0.0, bb = 0.0;
  // Partial sums over m = 0..p-1-j for j = p-1 down to 0 (m grows as j falls).
  for (size_t m = 0; m < p; ++m) {
    a_sum += m == 0 ? 1.0 : -phi[m - 1];
    b_sum += phi[p - 1 - m];
    aa += a_sum * a_sum;
    bb += b_sum * b_sum;
  }
  return aa - bb;
}

// Burg's two sums at order m, over t = m+1..n-1: cross = sum f_m(t) b_m(t-1) and
// energy = sum f_m(t)^2 + b_m(t-1)^2, with the forward and backward prediction errors
//   f_m(t) = sum_{i=0}^{m} a_i x_{t-i},   b_m(t) = sum_{i=0}^{m} a_i x_{t-m+i},   a_0 = 1
// (a_i = -phi_i). Burg's reflection coefficient is k = 2 cross / energy.
struct BurgSums {
  double cross = 0.0;
  double energy = 0.0;
};

// Four lanes of a sum (term t to lane (t - first) mod 4, the last n mod 4 to lane 0), so the
// order of the additions is fixed in the source and both METRO_SIMD_CLONES paths agree.
using Lanes4 = double __attribute__((vector_size(32)));

inline void Load4(const double* p, Lanes4* v) { std::memcpy(v, p, sizeof(Lanes4)); }
inline void Store4(double* p, const Lanes4& v) { std::memcpy(p, &v, sizeof(Lanes4)); }
inline double AddLanes(const Lanes4& s) { return (s[0] + s[1]) + (s[2] + s[3]); }

// One order of the lattice, m -> m + 1 with reflection coefficient k, from the errors of
// order m (fo, bo, valid from t = m) into fn, bn (from t = m + 1):
//   fn(t) = fo(t) - k bo(t-1),   bn(t) = bo(t-1) - k fo(t),
// and Burg's sums of order m + 1 over t = m+2..n-1 in the same pass: fn(t) bn(t-1), with
// bn(t-1) formed again from the old errors so no term waits for the previous one.
METRO_SIMD_CLONES
void LatticeStep(const double* __restrict fo, const double* __restrict bo, size_t m, size_t n,
                 double k, double* __restrict fn, double* __restrict bn, double* cross,
                 double* energy) {
  const size_t first = m + 1;
  if (first < n) {
    fn[first] = fo[first] - k * bo[first - 1];
    bn[first] = bo[first - 1] - k * fo[first];
  }
  Lanes4 c = {0.0, 0.0, 0.0, 0.0}, e = c;
  const Lanes4 kv = {k, k, k, k};
  size_t t = first + 1;
  for (; t + 4 <= n; t += 4) {
    Lanes4 f0, f1, b1, b2;
    Load4(fo + t, &f0);
    Load4(fo + t - 1, &f1);
    Load4(bo + t - 1, &b1);
    Load4(bo + t - 2, &b2);
    const Lanes4 f_new = f0 - kv * b1;
    const Lanes4 b_prev = b2 - kv * f1;
    Store4(fn + t, f_new);
    Store4(bn + t, b1 - kv * f0);
    c += f_new * b_prev;
    e += f_new * f_new + b_prev * b_prev;
  }
  for (; t < n; ++t) {
    const double f_new = fo[t] - k * bo[t - 1];
    const double b_prev = bo[t - 2] - k * fo[t - 1];
    fn[t] = f_new;
    bn[t] = bo[t - 1] - k * fo[t];
    c[0] += f_new * b_prev;
    e[0] += f_new * f_new + b_prev * b_prev;
  }
  *cross = AddLanes(c);
  *energy = AddLanes(e);
}

// The textbook lattice: the error series themselves, one pass over the record per order
// (LatticeStep), the errors of the new order written beside the old ones.
class ErrorSeriesBurg {
 public:
  // The errors of the order-m filter a (a[0] = 1) of the centred series d, and their sums.
  ErrorSeriesBurg(const std::vector<double>& d, const std::vector<double>& a)
      : f_(d.size()), b_(d.size()), f_next_(d.size()), b_next_(d.size()) {
    const size_t n = d.size();
    const size_t m = a.size() - 1;
    for (size_t t = m; t < n; ++t) {
      double ft = 0.0, bt = 0.0;
      for (size_t i = 0; i <= m; ++i) {
        ft += a[i] * d[t - i];
        bt += a[i] * d[t - m + i];
      }
      f_[t] = ft;
      b_[t] = bt;
    }
    for (size_t t = m + 1; t < n; ++t) {
      sums_.cross += f_[t] * b_[t - 1];
      sums_.energy += f_[t] * f_[t] + b_[t - 1] * b_[t - 1];
    }
  }
  // Burg's sums of the current order.
  BurgSums Sums() const { return sums_; }
  // Order m -> m + 1 with reflection coefficient k.
  void Update(size_t m, double k) {
    LatticeStep(f_.data(), b_.data(), m, f_.size(), k, f_next_.data(), b_next_.data(), &sums_.cross,
                &sums_.energy);
    f_.swap(f_next_);
    b_.swap(b_next_);
  }

 private:
  std::vector<double> f_, b_, f_next_, b_next_;
  BurgSums sums_;
};

// sum x_i in four lanes (lane i mod 4, the last n mod 4 terms in lane 0).
METRO_SIMD_CLONES
double LaneSum(const double* x, size_t n) {
  Lanes4 s = {0.0, 0.0, 0.0, 0.0};
  const size_t body = n / 4 * 4;
  for (size_t i = 0; i < body; i += 4) {
    Lanes4 v;
    Load4(x + i, &v);
    s += v;
  }
  for (size_t i = body; i < n; ++i) s[0] += x[i];
  return AddLanes(s);
}

// d_i = x_i - centre, and sum d_i^2 in four lanes (as LaneSum).
METRO_SIMD_CLONES
double CentreAndSquare(const double* x, size_t n, double centre, double* d) {
  Lanes4 s = {0.0, 0.0, 0.0, 0.0};
  const Lanes4 c = {centre, centre, centre, centre};
  const size_t body = n / 4 * 4;
  for (size_t i = 0; i < body; i += 4) {
    Lanes4 v;
    Load4(x + i, &v);
    v -= c;
    Store4(d + i, v);
    s += v * v;
  }
  for (size_t i = body; i < n; ++i) {
    d[i] = x[i] - centre;
    s[0] += d[i] * d[i];
  }
  return AddLanes(s);
}

// LaneSum (squared = false) or CentreAndSquare's sum of squares about `centre` (true) over
// one chunk of the record, added to *lanes; n must be a multiple of 4 except for the last
// chunk, so the lanes hold the same terms as the whole record's (and the same clones).
METRO_SIMD_CLONES
void AddLaneSums(const double* x, size_t n, double centre, bool squared, Lanes4* lanes) {
  const Lanes4 c = {centre, centre, centre, centre};
  const size_t body = n / 4 * 4;
  for (size_t i = 0; i < body; i += 4) {
    Lanes4 v;
    Load4(x + i, &v);
    if (squared) {
      v -= c;
      *lanes += v * v;
    } else {
      *lanes += v;
    }
  }
  for (size_t i = body; i < n; ++i) {
    const double v = squared ? x[i] - centre : x[i];
    (*lanes)[0] += squared ? v * v : v;
  }
}

// acc[l] = sum_{t=t0}^{t1-1} x_t x_{t+l} for l < lags: four lags at a time, each in four
// lanes over t (lane (t - t0) mod 4, the last (t1 - t0) mod 4 terms in lane 0), so the
// accumulators stay in registers and every METRO_SIMD_CLONES path gives the same bits.
METRO_SIMD_CLONES
void BlockLagProducts(const double* x, size_t t0, size_t t1, size_t lags, double* acc) {
  const size_t body = t0 + (t1 - t0) / 4 * 4;
  size_t l = 0;
  for (; l + 4 <= lags; l += 4) {
    Lanes4 a0 = {0.0, 0.0, 0.0, 0.0}, a1 = a0, a2 = a0, a3 = a0;
    for (size_t t = t0; t < body; t += 4) {
      Lanes4 xt, y0, y1, y2, y3;
      Load4(x + t, &xt);
      Load4(x + t + l, &y0);
      Load4(x + t + l + 1, &y1);
      Load4(x + t + l + 2, &y2);
      Load4(x + t + l + 3, &y3);
      a0 += xt * y0;
      a1 += xt * y1;
      a2 += xt * y2;
      a3 += xt * y3;
    }
    for (size_t t = body; t < t1; ++t) {
      a0[0] += x[t] * x[t + l];
      a1[0] += x[t] * x[t + l + 1];
      a2[0] += x[t] * x[t + l + 2];
      a3[0] += x[t] * x[t + l + 3];
    }
    acc[l] = AddLanes(a0);
    acc[l + 1] = AddLanes(a1);
    acc[l + 2] = AddLanes(a2);
    acc[l + 3] = AddLanes(a3);
  }
  for (; l < lags; ++l) {
    Lanes4 a0 = {0.0, 0.0, 0.0, 0.0};
    for (size_t t = t0; t < body; t += 4) {
      Lanes4 xt, y0;
      Load4(x + t, &xt);
      Load4(x + t + l, &y0);
      a0 += xt * y0;
    }
    for (size_t t = body; t < t1; ++t) a0[0] += x[t] * x[t + l];
    acc[l] = AddLanes(a0);
  }
}

// The same sums from the series' lag products (Vos, "A fast implementation of Burg's
// method", 2013): each sum is a quadratic form a' S a whose entries are windowed lag sums
//   G(u0, u1, l) = sum_{u=u0}^{u1} x_u x_{u+l} = c_l - head_l(u0) - tail_l(n - 1 - l - u1),
// c_l the full lag product, head_l(k) its first k terms and tail_l(k) its last k terms. The
// record is read once for c_0..c_{p+1} (O(n p)); every order then costs O(m^2), independent
// of n. Exact in exact arithmetic; in floating point its error grows with the filter's size
// against the error energy (see Conditioning), where the caller falls back to the lattice.
class LagProductBurg {
 public:
  // The lag products are summed in blocks of kBlock in double (the inner loop vectorizes)
  // and the blocks in extended precision, and the quadratic forms are formed in extended
  // precision too: their cancellation is what costs accuracy on strongly correlated series.
  using Wide = long double;
  static constexpr size_t kBlock = 512;

  LagProductBurg(const std::vector<double>& d, size_t max_order)
      : n_(d.size()), lags_(max_order + 2) {
    const size_t l_count = lags_;
    c_.assign(l_count, 0.0);
    // c_l for every lag in one pass: the inner loop over l keeps independent accumulators.
    const double* x = d.data();
    std::vector<double> block(l_count);
    for (size_t t0 = 0; t0 < FullEnd(); t0 += kBlock) {
      AddBlock(x, t0, std::min(FullEnd(), t0 + kBlock), block.data());
    }
    const auto at = [x](size_t i) { return x[i]; };
    AddTail(at);
    InitWindows(at);
  }

  // The same from a record read in chunks (ChunkReader): x_t - mean formed as above, the same
  // blocks and lanes, so c_l, the head and the tail are the same bits as in memory.
  static Result<std::unique_ptr<LagProductBurg>> FromChunks(const ChunkReader& read, size_t n,
                                                            double mean, size_t max_order) {
    auto burg = std::unique_ptr<LagProductBurg>(new LagProductBurg(n, max_order + 2));
    const size_t l_count = burg->lags_;
    const size_t full = burg->FullEnd();
    std::vector<double> x(kStreamChunk + l_count), block(l_count);
    for (size_t base = 0; base < full; base += kStreamChunk) {
      const size_t count = std::min(kStreamChunk + l_count, n - base);
      if (Status s = read(base, count, x.data()); !s.ok()) return s.error();
      for (size_t i = 0; i < count; ++i) x[i] -= mean;
      const size_t stop = std::min(full, base + kStreamChunk);
      for (size_t t0 = base; t0 < stop; t0 += kBlock) {
        burg->AddBlock(x.data(), t0 - base, std::min(stop, t0 + kBlock) - base, block.data());
      }
    }
    // The first and last 2 (p + 2) values: the tail sums and the head and tail windows.
    const size_t edge = std::min(n, 2 * l_count);
    std::vector<double> head(edge), tail(edge);
    if (Status s = read(0, edge, head.data()); !s.ok()) return s.error();
    if (Status s = read(n - edge, edge, tail.data()); !s.ok()) return s.error();
    for (double& v : head) v -= mean;
    for (double& v : tail) v -= mean;
    const size_t tail_begin = n - edge;
    const auto at = [&](size_t i) { return i < edge ? head[i] : tail[i - tail_begin]; };
    burg->AddTail(at);
    burg->InitWindows(at);
    return burg;
  }

  double c0() const { return static_cast<double>(c_[0]); }

  BurgSums Sums(const std::vector<double>& a) const {
    const size_t m = a.size() - 1;
    Wide forward = 0.0, backward = 0.0, cross = 0.0;
    for (size_t i = 0; i <= m; ++i) {
      for (size_t j = 0; j <= m; ++j) {
        const Wide aa = static_cast<Wide>(a[i]) * a[j];
        // Forward: sum_{t=m+1}^{n-1} x_{t-i} x_{t-j}; backward: x_{t-1-m+i} x_{t-1-m+j}.
        const size_t lo = std::min(i, j), hi = std::max(i, j);
        forward += aa * Window(hi - lo, m + 1 - hi, lo);
        backward += aa * Window(hi - lo, lo, m + 1 - hi);
        // Cross: x_{t-i} x_{t-1-m+j}; the first index leads the second by m + 1 - i - j.
        if (i + j <= m + 1) {
          cross += aa * Window(m + 1 - i - j, j, i);
        } else {
          cross += aa * Window(i + j - m - 1, m + 1 - i, m + 1 - j);
        }
      }
    }
    return {static_cast<double>(cross), static_cast<double>(forward + backward)};
  }

 private:
  LagProductBurg(size_t n, size_t lags) : n_(n), lags_(lags) { c_.assign(lags_, 0.0); }

  // Products x_t x_{t+l} of every lag are summed in kBlock blocks for t < FullEnd(), where
  // every lag has its partner; the rest one by one (AddTail).
  size_t FullEnd() const { return n_ > lags_ ? n_ - lags_ + 1 : 0; }
  void AddBlock(const double* x, size_t t0, size_t t1, double* block) {
    BlockLagProducts(x, t0, t1, lags_, block);
    for (size_t l = 0; l < lags_; ++l) c_[l] += block[l];
  }
  // at(i) is x_i for i >= FullEnd().
  template <typename At>
  void AddTail(const At& at) {
    for (size_t t = FullEnd(); t < n_; ++t) {
      for (size_t l = 0; l + t < n_; ++l) c_[l] += static_cast<Wide>(at(t)) * at(t + l);
    }
  }
  // head_l(k) = sum_{u<k} x_u x_{u+l}, tail_l(k) = sum of the last k products of lag l;
  // at(i) is x_i for the first and last 2 lags_ indices.
  template <typename At>
  void InitWindows(const At& at) {
    const size_t l_count = lags_;
    head_.assign(l_count * (l_count + 1), 0.0);
    tail_.assign(l_count * (l_count + 1), 0.0);
    for (size_t l = 0; l < l_count; ++l) {
      for (size_t k = 1; k <= l_count; ++k) {
        const size_t u_head = k - 1;
        const Wide h = u_head + l < n_ ? static_cast<Wide>(at(u_head)) * at(u_head + l) : 0.0L;
        Head(l, k) = Head(l, k - 1) + h;
        const bool in_range = n_ >= l + k;
        const size_t u_tail = in_range ? n_ - l - k : 0;
        Tail(l, k) =
            Tail(l, k - 1) + (in_range ? static_cast<Wide>(at(u_tail)) * at(u_tail + l) : 0.0L);
      }
    }
  }

  // G with the first head_terms and the last tail_terms products of lag l left out.
  Wide Window(size_t l, size_t head_terms, size_t tail_terms) const {
    return c_[l] - Head(l, head_terms) - Tail(l, tail_terms);
  }
  Wide& Head(size_t l, size_t k) { return head_[l * (lags_ + 1) + k]; }
  Wide Head(size_t l, size_t k) const { return head_[l * (lags_ + 1) + k]; }
  Wide& Tail(size_t l, size_t k) { return tail_[l * (lags_ + 1) + k]; }
  Wide Tail(size_t l, size_t k) const { return tail_[l * (lags_ + 1) + k]; }

  size_t n_;
  size_t lags_;
  std::vector<Wide> c_, head_, tail_;
};

// Largest (sum |a_i|)^2 c_0 / (energy / 2) at which the lag-product sums are used: each sum
// cancels the quadratic form's terms (about (sum |a_i|)^2 c_0 in size) down to the error
// energy, so its relative rounding error is about this ratio times the extended precision's
// 1e-19 plus the double-precision blocks' 1e-16 per lag product. Beyond it the lattice takes
// over. Measured against an 80-bit reference lattice (tests/stats/spectral_mean_test.cpp):
// within 1e-10 of the reference on random walks and smooth series, where the double lattice
// itself is off by up to 2e-9.
constexpr double kMaxLagProductConditioning = 1e4;

double Conditioning(const std::vector<double>& a, double c0, double energy) {
  double l1 = 0.0;
  for (double v : a) l1 += std::abs(v);
  return energy > 0.0 ? l1 * l1 * c0 / (0.5 * energy) : HUGE_VAL;
}

}  // namespace

namespace {

// Burg's recursion over orders m = 0, 1, ... from the lag products (`fast`, or the lattice
// from the start when it is null), the AIC choice and the estimate. `d` is the centred record
// for the lattice, null when it is not in memory (the streaming mode): a fallback then
// returns an Error.
Result<ArSpectralResult> FitOrders(size_t n, double e0, int max_order,
                                   std::unique_ptr<LagProductBurg> fast,
                                   const std::vector<double>* d, const ArSpectralOptions& options) {
  const double dn = static_cast<double>(n);
  std::unique_ptr<ErrorSeriesBurg> lattice;
  if (!fast) lattice = std::make_unique<ErrorSeriesBurg>(*d, std::vector<double>{1.0});
  std::vector<double> a{1.0}, next;
  double e = e0 / dn;
  double best_aic = dn * std::log(e);
  ArSpectralResult best;
  best.innovation_variance = e;
  for (int p = 1; p <= max_order; ++p) {
    const size_t m = static_cast<size_t>(p - 1);
    BurgSums s;
    if (fast) {
      s = fast->Sums(a);
      if (Conditioning(a, fast->c0(), s.energy) > kMaxLagProductConditioning) {
        // Too much cancellation for the lag products: the lattice from here on.
        if (d == nullptr) {
          return MakeError(fmt::format(
              "the autoregressive fit of this strongly correlated series needs the error-series "
              "lattice from order {}, which reads the whole record in memory: not available in "
              "streaming mode (run without --stream)",
              p));
        }
        fast.reset();
        lattice = std::make_unique<ErrorSeriesBurg>(*d, a);
        ++best.lattice_fallbacks;
      }
    }
    if (lattice) s = lattice->Sums();
    if (!(s.energy > 0.0)) break;
    const double k = 2.0 * s.cross / s.energy;  // |k| <= 1 (Cauchy-Schwarz): stationary.
    // Levinson update: a'_j = a_j - k a_{p-j}, a'_p = -k (phi_p = k).
    next.assign(static_cast<size_t>(p) + 1, 0.0);
    next[0] = 1.0;
    for (size_t j = 1; j < static_cast<size_t>(p); ++j) {
      next[j] = a[j] - k * a[static_cast<size_t>(p) - j];
    }
    next[static_cast<size_t>(p)] = -k;
    a.swap(next);
    if (lattice) lattice->Update(m, k);
    e *= 1.0 - k * k;
    if (!(e > 0.0)) break;
    const double aic = dn * std::log(e) + 2.0 * p;  // Akaike 1974
    if (aic < best_aic) {
      best_aic = aic;
      best.order = p;
      best.phi.assign(a.size() - 1, 0.0);
      for (size_t j = 1; j < a.size(); ++j) best.phi[j - 1] = -a[j];
      best.innovation_variance = e;
    }
    // The AIC order's innovation variance is at most e exp(2 p / n) (spectral_mean.hpp); the
    // margin covers the rounding of the AIC comparisons.
    if (options.stop_below_innovation_variance > 0.0 &&
        e * std::exp(2.0 * p / dn) * (1.0 + 1e-9) < options.stop_below_innovation_variance) {
      ArSpectralResult stopped;
      stopped.order = p;
      stopped.innovation_variance = e;
      stopped.lattice_fallbacks = best.lattice_fallbacks;
      stopped.stopped_below = true;
      return stopped;
    }
  }
  double sum_phi = 0.0;
  for (double v : best.phi) sum_phi += v;
  // A(1) = 1 - sum phi > 0 for a stationary model (no root of A(z) in |z| <= 1).
  const double a1_fitted = std::max(1.0 - sum_phi, 1e-12);
  // The fitted persistence sum phi is biased low by about (1 + 3 phi) / n (AR(1) with the
  // mean estimated: Marriott & Pope, Biometrika 41 (1954) 390; Kendall, Biometrika 41
  // (1954) 403), which makes u too small by ~15 % at phi = 0.9, n = 200. The correction is
  // applied to the sum, and at most halves A(1).
  const double a1 = std::max(a1_fitted - (1.0 + 3.0 * sum_phi) / dn, 0.5 * a1_fitted);
  best.sum_phi = sum_phi;
  best.a1 = a1;
  best.long_run_variance = best.innovation_variance / (a1 * a1);
  best.u_mean = std::sqrt(best.long_run_variance / dn);
  const double q = best.order > 0 ? GohbergSemencul11(best.phi) : 0.0;
  // Delta method on the fitted estimates (their own spread, about the fitted A(1)).
  const double r2 = 0.5 / dn + std::max(q, 0.0) / (dn * a1_fitted * a1_fitted);
  best.relative_u_of_u = std::sqrt(r2);
  best.dof = std::min(0.5 / r2, dn - 1.0);  // JCGM 100:2008 G.4.2
  if (!std::isfinite(best.u_mean)) {
    return MakeError("the autoregressive long-run variance overflows double precision");
  }
  return best;
}

int MaxOrder(const ArSpectralOptions& options, size_t n) {
  return std::min(options.max_order > 0 ? options.max_order : DefaultMaxOrder(n),
                  static_cast<int>(n) - 2);
}

}  // namespace

Result<ArSpectralResult> ArSpectralMeanUncertainty(const double* values, size_t n,
                                                   const ArSpectralOptions& options) {
  if (n < 4) {
    return MakeError(fmt::format("{} observations: an autoregressive fit needs at least 4", n));
  }
  const double mean = LaneSum(values, n) / static_cast<double>(n);
  std::vector<double> d(n);
  const double e0 = CentreAndSquare(values, n, mean, d.data());
  if (!std::isfinite(e0)) return MakeError("the series is not finite");
  if (e0 == 0.0) return MakeError("a constant series has no autocorrelation");
  const int max_order = MaxOrder(options, n);
  std::unique_ptr<LagProductBurg> fast;
  if (options.method == ArSpectralOptions::Method::kLagProducts) {
    fast = std::make_unique<LagProductBurg>(d, static_cast<size_t>(std::max(max_order, 0)));
  }
  return FitOrders(n, e0, max_order, std::move(fast), &d, options);
}

Result<ArSpectralResult> ArSpectralMeanUncertaintyChunked(const ChunkReader& read, size_t n,
                                                          const ArSpectralOptions& options) {
  if (n < 4) {
    return MakeError(fmt::format("{} observations: an autoregressive fit needs at least 4", n));
  }
  if (options.method != ArSpectralOptions::Method::kLagProducts) {
    return MakeError("the lattice method reads the record in memory: not available in chunks");
  }
  // The mean and e0 in the lanes of LaneSum and CentreAndSquare (chunks are whole lanes).
  std::vector<double> x(kStreamChunk);
  double sum = 0.0;
  {
    Lanes4 lanes = {0.0, 0.0, 0.0, 0.0};
    for (size_t base = 0; base < n; base += kStreamChunk) {
      const size_t count = std::min(kStreamChunk, n - base);
      if (Status s = read(base, count, x.data()); !s.ok()) return s.error();
      AddLaneSums(x.data(), count, 0.0, false, &lanes);
    }
    sum = AddLanes(lanes);
  }
  const double mean = sum / static_cast<double>(n);
  double e0 = 0.0;
  {
    Lanes4 lanes = {0.0, 0.0, 0.0, 0.0};
    for (size_t base = 0; base < n; base += kStreamChunk) {
      const size_t count = std::min(kStreamChunk, n - base);
      if (Status s = read(base, count, x.data()); !s.ok()) return s.error();
      AddLaneSums(x.data(), count, mean, true, &lanes);
    }
    e0 = AddLanes(lanes);
  }
  if (!std::isfinite(e0)) return MakeError("the series is not finite");
  if (e0 == 0.0) return MakeError("a constant series has no autocorrelation");
  const int max_order = MaxOrder(options, n);
  auto fast =
      LagProductBurg::FromChunks(read, n, mean, static_cast<size_t>(std::max(max_order, 0)));
  if (!fast.ok()) return fast.error();
  return FitOrders(n, e0, max_order, std::move(fast).value(), nullptr, options);
}

}  // namespace metro
