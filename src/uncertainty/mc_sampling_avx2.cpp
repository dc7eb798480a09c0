// Bailey's t arithmetic built for AVX2 + FMA (see src/uncertainty/CMakeLists.txt); called by
// mc_sampling.cpp only when the CPU reports both. Eigen is renamed in this translation unit
// so that none of its inline functions, compiled here with AVX2 instructions, can be picked
// by the linker for the baseline build of the same function elsewhere in the library.
#include <cstddef>

#define Eigen MetroEigenAvx2
#define METRO_MC_KERNEL_NAMESPACE avx2
#include "uncertainty/mc_bailey_kernel.hpp"

namespace metro {
namespace internal {

void BaileyTransformAvx2(const double* u, const double* w, size_t n, double nu, double location,
                         double scale, double* e_scratch, double* out) {
  avx2::BaileyTransform(u, w, n, nu, location, scale, e_scratch, out);
}

}  // namespace internal
}  // namespace metro
