#pragma once
/** \file NearestTwo.h
 * The nearest and second-nearest of a stream of candidate distances: what a descriptor match's
 * ratio test (nearest < ratio x second nearest) needs.
 */
#include <limits>
#include <type_traits>

namespace keygrid::core
{
/** Feed the candidates' distances with add() in candidate order; a tie keeps the earlier
 * candidate as the nearest. With fewer than two candidates the missing distances are infinite. */
template <typename T>
struct NearestTwo
{
	static_assert(std::is_floating_point_v<T>, "NearestTwo: distances are floating point");
	T best{std::numeric_limits<T>::infinity()};
	T second{std::numeric_limits<T>::infinity()};
	int index{-1};  //!< the nearest candidate, -1 before the first

	void add(T d, int candidate)
	{
		if (d < best)
		{
			second = best;
			best = d;
			index = candidate;
		}
		else if (d < second)
			second = d;
	}
};

}  // namespace keygrid::core
