// Seed 000's friction test end to end: simulate (7 supply pressures x 28
// meter-out openings, true friction = Annex B per p0), extract the
// quasi-static medians, fit eq. 4 and eq. 8 (p = pAB-), compare with the
// paper (Annex A: R2 0.9797, Annex C: R2 0.9974), plot.
//   ./build/examples/friction_test/friction_test_example [OUT_DIR]   (default out/friction_test)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>

#include "components/fit/friction_fit.hpp"
#include "friction_experiment.hpp"

using namespace pneumo;

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "out/friction_test";
  std::filesystem::create_directories(out);
  examples::FrictionTestOptions opt;
  opt.netlist = std::string(PNEUMO_SOURCE_DIR) + "/examples/friction_test/friction_rig.yaml";
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<examples::FrictionTestPoint> pts;
  try {
    pts = examples::run_friction_test(opt);
  } catch (const std::exception& e) {
    std::cerr << "friction_test_example: " << e.what() << "\n";
    return 1;
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string csv = out + "/points.csv";
  examples::write_friction_points(csv, pts);
  double max_dev = 0, max_spread = 0;
  int failed_late = 0;
  for (const auto& p : pts) {
    failed_late += p.failed_after_window;
    max_dev = std::max(max_dev, std::abs(p.F - p.F_model));
    max_spread = std::max(max_spread, p.v_spread);
  }
  std::printf("%zu runs in %.1f s; wrote %s\n", pts.size(), secs, csv.c_str());
  std::printf("force balance vs the cylinder's F_friction: max |difference| %.3g N; max speed spread in a window %.3g\n",
              max_dev, max_spread);
  if (failed_late)
    std::printf("%d runs failed in the solver after the quasi-static window (their window was complete)\n",
                failed_late);

  const fit::DataTable d = fit::read_data_table(csv);
  const auto points = fit::friction_points(d, components::FrictionPressure::ab_minus);
  const auto r4 = fit::fit_friction(fit::FrictionModel::eq4, points, fit::default_friction_parameters(fit::FrictionModel::eq4));
  const auto r8 = fit::fit_friction(fit::FrictionModel::eq8, points, fit::default_friction_parameters(fit::FrictionModel::eq8));
  std::cout << "eq. 4, p = pAB- (paper, Annex A: RSS 4.29e3 N^2, R2 0.9797):\n" << fit::format_report(r4, "N^2");
  std::cout << "eq. 8, p = pAB- (paper, Annex C: RSS 526 N^2, R2 0.9974):\n" << fit::format_report(r8, "N^2");

  // Data and both fits at every point, per supply pressure, for gnuplot.
  const std::string dat = out + "/fits.dat";
  {
    std::ofstream f(dat);
    std::map<double, std::vector<std::size_t>> by_p0;
    for (std::size_t i = 0; i < pts.size(); ++i) by_p0[pts[i].p0_bar_rel].push_back(i);
    for (const auto& [p0, idx] : by_p0) {
      f << "# p0 = " << p0 << " bar_rel\n# v F F_eq4 F_eq8 pAB-\n";
      for (auto i : idx)
        f << points[i].v << " " << points[i].F << " "
          << fit::friction_model_force(fit::FrictionModel::eq4, r4.values(), points[i].v, points[i].p_bar) << " "
          << fit::friction_model_force(fit::FrictionModel::eq8, r8.values(), points[i].v, points[i].p_bar) << " "
          << points[i].p_bar << "\n";
      f << "\n\n";
    }
  }
  char title4[128], title8[128];
  std::snprintf(title4, sizeof title4, "eq. 4 (pAB-): R^2 = %.4f, RSS = %.0f N^2", r4.r2, r4.rss);
  std::snprintf(title8, sizeof title8, "eq. 8 (pAB-): R^2 = %.4f, RSS = %.0f N^2", r8.r2, r8.rss);
  const std::string gp = out + "/friction_fit.gp";
  {
    std::ofstream g(gp);
    g << "set terminal pngcairo size 1200,480 font 'sans,10'\nset output '" << out << "/friction_fit.png'\n"
      << "set multiplot layout 1,2\nset logscale x\nset xlabel 'piston speed v [m/s]'\n"
      << "set ylabel 'friction force F [N]'\nset key top left\nset grid\n"
      << "labels = '2.07 3.127 4.115 5.14 6.13 7.085 8.075'\n";
    for (int k = 0; k < 2; ++k) {
      g << "set title '" << (k == 0 ? title4 : title8) << "'\n"
        << "plot for [i=0:6] '" << dat << "' index i using 1:2 with points pt 6 lc i+1 title 'p0 = '.word(labels,i+1).' bar_rel' noenhanced, \\\n"
        << "     for [i=0:6] '" << dat << "' index i using 1:" << (k == 0 ? 3 : 4) << " with lines lc i+1 notitle\n";
    }
    g << "unset multiplot\n";
  }
  if (std::system(("gnuplot " + gp).c_str()) != 0) {
    std::cerr << "friction_test_example: gnuplot failed on " << gp << "\n";
    return 1;
  }
  std::printf("plotted %s/friction_fit.png\n", out.c_str());
  std::printf("R2: eq. 4 %.4f, eq. 8 %.4f (paper: 0.9797, 0.9974)\n", r4.r2, r8.r2);
  return r8.r2 > r4.r2 ? 0 : 1;
}
