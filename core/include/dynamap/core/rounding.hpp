#pragma once

#include <cmath>

namespace dynamap {

/// std::lround, inline (built for plain x86-64, without SSE4.1, std::lround is a libm call that
/// costs more than the rounding): the integer nearest x, halves away from zero. Exact: the
/// fraction x - trunc(x) has no rounding error for |x| < 2^31; beyond, std::lround itself.
inline long roundHalfAway(double x) {
  if (!(std::fabs(x) < 2147483648.0)) return std::lround(x);
  long i = static_cast<long>(x);  // towards zero
  const double fraction = x - static_cast<double>(i);
  if (fraction >= 0.5) {
    ++i;
  } else if (fraction <= -0.5) {
    --i;
  }
  return i;
}

/// std::lround of a float: the same as of the double it converts to exactly.
inline long roundHalfAway(float x) { return roundHalfAway(static_cast<double>(x)); }

}  // namespace dynamap
