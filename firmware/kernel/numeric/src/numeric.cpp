// Explicit instantiations: compiles every header of maglev_numeric with the
// project's strict warnings, for host and for arm-none-eabi.
#include "maglev/numeric/fixed.hpp"
#include "maglev/numeric/saturation.hpp"
#include "maglev/numeric/scalar_traits.hpp"
#include "maglev/numeric/sin_cos.hpp"

namespace maglev::numeric {

template class Fixed<24>;
template class Fixed<28>;
template class Wide<32>;
template struct ScalarTraits<float>;
template struct ScalarTraits<Q7_24>;

// Compile-time checks of the table and the rounding rules.
static_assert(kQuarterSineTable[0] == 0);
static_assert(kQuarterSineTable[kSinTableSize] == (1 << 30));
static_assert(sin_q30(0x40000000u) == (1 << 30));
static_assert(cos_q30(0) == (1 << 30));
static_assert(sin_q30(0xC0000000u) == -(1 << 30));
static_assert((Q7_24::from_double(1.5) * Q7_24::from_double(2.0)).raw() == 3 * (1 << 24));
static_assert(Q7_24::from_raw(1).raw() * 0 == 0);

}  // namespace maglev::numeric
