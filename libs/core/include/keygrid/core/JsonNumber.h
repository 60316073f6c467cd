#pragma once
/** \file JsonNumber.h
 * A number as JSON text: `digits` significant digits (printf %g), and `null` for NaN and
 * infinities, which JSON cannot represent.
 */
#include <cmath>
#include <cstdio>
#include <string>

namespace keygrid::core
{
inline std::string jsonNumber(double v, int digits = 9)
{
	if (!std::isfinite(v)) return "null";
	char b[64];
	std::snprintf(b, sizeof(b), "%.*g", digits, v);
	return b;
}
}  // namespace keygrid::core
