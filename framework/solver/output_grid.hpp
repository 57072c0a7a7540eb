// The output times of a run: t_start + k * interval, then t_end.
#pragma once

#include <cmath>

namespace pneumo {

struct OutputGrid {
  OutputGrid(double t_start, double t_end, double interval)
      : t_start(t_start), t_end(t_end), interval(interval),
        n_out(static_cast<long>(std::ceil((t_end - t_start) / interval - 1e-9))) {}
  double time(long j) const { return j >= n_out ? t_end : t_start + j * interval; }
  // The next output time not yet written, if any.
  bool pending() const { return k <= n_out; }
  double next() const { return time(k); }

  double t_start, t_end, interval;
  long n_out;
  long k = 1;  // index of the next output time (0 is t_start)
};

}  // namespace pneumo
