#pragma once
// FFTW's planner (plan creation and destruction) is not thread-safe; execution of a plan is. Every
// caller that makes or destroys an FFTW plan, in any layer, holds this one mutex: two mutexes would
// not exclude each other.
#include <mutex>

namespace caustics {

std::mutex& fftw_planner_mutex();

}  // namespace caustics
