#pragma once
/** \file FloorToInt.h
 * Integer floor for the grids' inner loops.
 */
#include <cstdint>

namespace keygrid
{
/** floor(x) as int32 without a libm call (baseline x86-64 has no SSE4.1 round instruction);
 * exact for |x| < 2^31. */
inline int32_t floorToInt(double x)
{
	const int32_t i = static_cast<int32_t>(x);
	return i - static_cast<int32_t>(x < static_cast<double>(i));
}

}  // namespace keygrid
