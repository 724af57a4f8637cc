#include <caustics/util/fftw_lock.hpp>

namespace caustics {

std::mutex& fftw_planner_mutex() {
    static std::mutex m;
    return m;
}

}  // namespace caustics
