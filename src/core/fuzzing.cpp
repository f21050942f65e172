#include "core/fuzzing.h"

#ifdef VKMESH_FUZZING_HOOKS
#include <atomic>

namespace vkmesh::fuzzing {

namespace {
std::atomic<bool> g_active{false};
}

bool active() { return g_active.load(std::memory_order_relaxed); }
void activate() { g_active.store(true, std::memory_order_relaxed); }

}  // namespace vkmesh::fuzzing
#endif
