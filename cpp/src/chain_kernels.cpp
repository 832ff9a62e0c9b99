// A chain's batch kernels (spotkin/kernels/chain.hpp), one clone per instruction-set
// level and precision. This unit is compiled with -ffp-contract=off (CMakeLists.txt).
#include "spotkin/kernels/chain.hpp"

#include "spotkin/chain_lanes.hpp"
#include "spotkin/isa.hpp"
#include "spotkin/point_jacobian.hpp"

namespace spotkin::kernels {

// At AVX-512 a double block's poses leave through 8 x 8 transposes (store_rows).
SPOTKIN_CLONES((), void, chain_fk, (const Chain<double>& c, const double* q, double* out, std::ptrdiff_t n),
               (c, q, out, n),
  chain_lanes::forward_batch<kIsa == Isa::Avx512>(c, q, out, n);
)
SPOTKIN_CLONES((), void, chain_fk, (const Chain<float>& c, const float* q, float* out, std::ptrdiff_t n),
               (c, q, out, n),
  chain_lanes::forward_batch(c, q, out, n);
)
SPOTKIN_CLONES((), void, chain_frames, (const Chain<double>& c, const double* q, double* out, std::ptrdiff_t n),
               (c, q, out, n),
  chain_lanes::frames_batch(c, q, out, n);
)
SPOTKIN_CLONES((), void, chain_frames, (const Chain<float>& c, const float* q, float* out, std::ptrdiff_t n),
               (c, q, out, n),
  chain_lanes::frames_batch(c, q, out, n);
)
SPOTKIN_CLONES((), void, chain_jacobian,
               (const Chain<double>& c, const double* q, double* out, std::ptrdiff_t n, int rows, bool in_tool_frame),
               (c, q, out, n, rows, in_tool_frame),
  chain_lanes::jacobian_batch(c, q, out, n, rows, in_tool_frame);
)
// At AVX-512 a float block is staged by entry and stored through 8 x 8 transposes (docs/isa.md).
SPOTKIN_CLONES((), void, chain_jacobian,
               (const Chain<float>& c, const float* q, float* out, std::ptrdiff_t n, int rows, bool in_tool_frame),
               (c, q, out, n, rows, in_tool_frame),
  chain_lanes::jacobian_batch<kIsa == Isa::Avx512>(c, q, out, n, rows, in_tool_frame);
)
SPOTKIN_CLONES((), void, chain_point_jacobian,
               (const Chain<double>& c, const double* q, double* out, std::ptrdiff_t n, int rows, int point,
                int frame),
               (c, q, out, n, rows, point, frame),
  point_jacobian_batch(c, q, out, n, rows, point, frame);
)
SPOTKIN_CLONES((), void, chain_point_jacobian,
               (const Chain<float>& c, const float* q, float* out, std::ptrdiff_t n, int rows, int point, int frame),
               (c, q, out, n, rows, point, frame),
  point_jacobian_batch(c, q, out, n, rows, point, frame);
)

}  // namespace spotkin::kernels
