// The next run that would decide (docs/how-to/diagnose.md): candidates the
// measured runs cannot tell apart often differ strongly at another operating
// point. Over the operating-point parameters the runs vary (within the range
// they span, or a range the user gives), the search looks for the point
// where the candidates' fitted models lie furthest apart in the measured
// signals: the smallest pairwise separation of the group, each pair's
// separation being that of its best signal - RMS over the run's samples of
// (a - b) / sigma, the measure the sensor choice uses (sensors.hpp), so that
// "n noise sd apart" reads the same in both. In the spirit of optimal
// experiment design for model discrimination (Box and Hill 1967): the run
// whose outcome the rival models predict most differently.
//
// Cheap by construction: a coarse grid over the parameters in scaled
// coordinates (9 levels for one parameter, fewer for more, at most kGridPoints
// points) and the
// measured runs' own points, then a local pattern search from the best;
// every member simulated once per point, points in parallel. A point at
// which a member's simulation fails is skipped and counted, never scored.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace pneumo::diagnose {

struct ExperimentAxis {  // one operating-point parameter the next run may set
  std::string name;
  double lower = 0, upper = 0;  // SI
};

// The signals of the template run (at its sample times) for group member
// `member` at `point` (one SI value per axis); empty when the run fails.
using MemberSimulation = std::function<std::vector<std::vector<double>>(int member, const std::vector<double>& point)>;

struct NextRunSearch {
  std::vector<ExperimentAxis> axes;
  std::vector<std::string> members;                  // at least two
  std::vector<double> sigma;                         // noise per signal of the template run
  std::vector<std::vector<double>> measured_points;  // the runs' operating points on the axes (SI)
  MemberSimulation simulate;
  int threads = 2;
};

struct NextRunFound {
  bool found = false;  // some point had every member run
  std::vector<double> point;                  // SI, per axis
  double separation = 0;                      // the group's smallest pairwise separation there (noise sd)
  double separation_measured = 0;             // the same, best over the measured runs' points
  int member_a = 0, member_b = 1;             // the closest pair there
  int signal = -1;                            // the signal that separates them most
  std::vector<double> d2;                     // that signal's ((a - b) / sigma)^2 per sample
  long simulations = 0, failed = 0, points = 0;
};

inline constexpr int kGridPoints = 64;  // the coarse grid's cap

NextRunFound search_next_run(const NextRunSearch& s);

}  // namespace pneumo::diagnose
