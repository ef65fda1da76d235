// The build's arithmetic (CMakeLists.txt: TUMBLE_AVX2, -mno-fma, -ffp-contract=off): every
// product and every sum rounds on its own, so a build with AVX2 and one for any x86-64 give
// the same bits. The tests are compiled with the engine's flags.
#include <gtest/gtest.h>

#include <cmath>

namespace {

// a·b = 1 − 2⁻⁶⁰ rounds to 1, so a·b − 1 is 0 when the product rounds before the sum; a fused
// multiply-add (one rounding) gives −2⁻⁶⁰. The inputs are volatile: nothing is folded early.
TEST(Build, ProductsAndSumsRoundSeparately) {
  volatile double a = 1.0 + std::ldexp(1.0, -30);
  volatile double b = 1.0 - std::ldexp(1.0, -30);
  volatile double c = -1.0;
  const double x = a, y = b, z = c;
  EXPECT_EQ(x * y + z, 0.0) << "a product and a sum were contracted into a fused multiply-add";
  EXPECT_EQ(std::fma(x, y, z), -std::ldexp(1.0, -60)) << "the check itself: fma rounds once";
}

#ifdef __FMA__
TEST(Build, NoFusedMultiplyAddInstructions) {
  FAIL() << "built with FMA enabled: Eigen's packet math would use it and change the bits";
}
#endif

}  // namespace
