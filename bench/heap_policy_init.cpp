// Every benchmark program starts with the heap policy the `caustics` program applies in main()
// (util/heap_policy.hpp), so that a benchmark times the frames a run times.
#include <caustics/util/heap_policy.hpp>

namespace {
const bool g_heap_policy = caustics::apply_heap_policy();
}  // namespace
