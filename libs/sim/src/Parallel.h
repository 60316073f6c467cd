#pragma once
// Private: splits image rows among threads. Every row is computed independently, so the result
// does not depend on the number of threads or their schedule.
#include <functional>

namespace keygrid::sim
{
/** Calls f(r0, r1) on disjoint row ranges covering [0, rows). threads = 0: all cores. */
void parallelRows(int rows, unsigned threads, const std::function<void(int, int)>& f);

}  // namespace keygrid::sim
