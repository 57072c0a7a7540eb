// The one way the framework runs independent work items on threads (sweeps,
// sensitivity designs, the diagnosis's simulations): fork-join over an index
// range, the calling thread working too.
#pragma once

#include <functional>

namespace pneumo {

// Calls work(worker, i) once for each i in [0, n), on min(threads, n)
// threads; `worker` (0 .. threads-1) names the calling thread, for state
// of its own (each worker id is used by one thread only). Indices are
// claimed in increasing order. After an exception no further index is
// claimed; the first one is rethrown once every thread has finished.
void parallel_for(long n, int threads, const std::function<void(int worker, long i)>& work);

}  // namespace pneumo
