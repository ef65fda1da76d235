#pragma once
/// Series of the rotation formulas, written once for a double and for four SIMD lanes
/// (lanes.hpp), so that each lane rounds as the scalar does. Internal to the engine; pure
/// functions, thread-safe.

namespace tumble {

/// a = sin θ/θ and b = (1 − cos θ)/θ² from t = θ² < 0.25, by their Taylor series in θ² to θ¹²
/// ((−1)ᵏ/(2k+1)! and (−1)ᵏ/(2k+2)!, k = 0…6, in Horner form): math.cpp says why.
template <class T>
[[gnu::always_inline]] inline void sinc_versine_series(T t, T& a, T& b) {
  a = 1.0 + t * (-1.0 / 6 + t * (1.0 / 120 + t * (-1.0 / 5040 + t * (1.0 / 362880 +
      t * (-1.0 / 39916800 + t * (1.0 / 6227020800 + t * (-1.0 / 1307674368000.0)))))));
  b = 0.5 + t * (-1.0 / 24 + t * (1.0 / 720 + t * (-1.0 / 40320 + t * (1.0 / 3628800 +
      t * (-1.0 / 479001600 + t * (1.0 / 87178291200.0 + t * (-1.0 / 20922789888000.0)))))));
}

}  // namespace tumble
