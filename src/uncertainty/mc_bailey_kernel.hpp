// The arithmetic of Bailey's t sampler (mc_sampling.hpp) over a block, as Eigen array
// expressions. Included by mc_sampling.cpp (baseline instruction set) and by
// mc_sampling_avx2.cpp (compiled with -mavx2 -mfma, its own renamed copy of Eigen), each
// inside its own namespace METRO_MC_KERNEL_NAMESPACE, so the two builds share no symbol.
//
//   e = -2 ln(w) / nu >= 0
//   x = location + scale u sqrt(nu expm1(e) / w)
// expm1(e) = exp(e) - 1 for e >= 1e-3 (relative error < 3e-13), else its Taylor series to
// e^5/120 (relative error < 2e-15).
#pragma once

#include <Eigen/Core>
#include <cstddef>

#ifndef METRO_MC_KERNEL_NAMESPACE
#error "define METRO_MC_KERNEL_NAMESPACE before including mc_bailey_kernel.hpp"
#endif

namespace metro {
namespace internal {
namespace METRO_MC_KERNEL_NAMESPACE {

// u, w: the accepted disc points; e: scratch; all n long.
inline void BaileyTransform(const double* u_in, const double* w_in, size_t n, double nu,
                            double location, double scale, double* e_scratch, double* out) {
  using ConstArray = Eigen::Map<const Eigen::ArrayXd>;
  using Array = Eigen::Map<Eigen::ArrayXd>;
  const Eigen::Index size = static_cast<Eigen::Index>(n);
  ConstArray u(u_in, size);
  ConstArray w(w_in, size);
  Array e(e_scratch, size);
  Array x(out, size);
  e = w.log() * (-2.0 / nu);
  x = e.exp() - 1.0;
  for (size_t k = 0; k < n; ++k) {
    const double ek = e_scratch[k];
    if (ek < 1e-3) {
      out[k] = ek * (1.0 + ek * (1.0 / 2.0 + ek * (1.0 / 6.0 + ek * (1.0 / 24.0 + ek / 120.0))));
    }
  }
  x = location + scale * u * (nu * x / w).sqrt();
}

}  // namespace METRO_MC_KERNEL_NAMESPACE
}  // namespace internal
}  // namespace metro
