// Driver for the independent reference of the basic end-cushioning rig:
// runs p_supply in {5, 7} bar abs x z_EC in {0.1, 1.5, 6.0} rev at m_load 3.7 kg
// and prints the cushioning figures, solver statistics and wall time per run
// (median of 20 runs at the default output interval of 1 ms).
//
// Usage: pneumo_rig_reference_main [n_timing_runs]
#include "cushion_rig_reference.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

using namespace pneumo_reference;

namespace {

struct Figures {
    double t_entry = NAN, v_entry = NAN;      // x crosses stroke - cushion_length
    double t_reach = NAN;                     // x >= stroke - 0.1 mm
    double t_contact = NAN, v_impact = NAN;   // x >= stroke (head / elastic stop)
    double rebound_before_contact = 0.0;      // max backward travel after entry, before contact
    double rebound_after_contact = 0.0;       // max backward travel after contact
    double p_EC_peak = 0.0;                   // max p_EC from cushion entry on
    double T_EC_min = 1e300, T_EC_max = 0.0, t_T_EC_min = NAN;  // whole run
    double v_max = 0.0;
};

// linear interpolation of the first upward crossing of `level` by x
bool crossing(const std::vector<RigSample>& s, double level, std::size_t& idx, double& t,
              double& v) {
    for (std::size_t i = 1; i < s.size(); ++i) {
        if (s[i - 1].x < level && s[i].x >= level) {
            const double w = (level - s[i - 1].x) / (s[i].x - s[i - 1].x);
            t = s[i - 1].t + w * (s[i].t - s[i - 1].t);
            v = s[i - 1].v + w * (s[i].v - s[i - 1].v);
            idx = i;
            return true;
        }
    }
    return false;
}

Figures analyse(const RigParams& P, const std::vector<RigSample>& s) {
    Figures F;
    for (const auto& r : s) {
        if (r.T_EC < F.T_EC_min) F.t_T_EC_min = r.t;
        F.T_EC_min = std::min(F.T_EC_min, r.T_EC);
        F.T_EC_max = std::max(F.T_EC_max, r.T_EC);
        F.v_max = std::max(F.v_max, r.v);
    }
    std::size_t i_entry = s.size(), i_contact = s.size(), i_reach = s.size();
    double dummy;
    if (!crossing(s, P.stroke - P.cushion_length, i_entry, F.t_entry, F.v_entry)) return F;
    for (std::size_t i = i_entry; i < s.size(); ++i) F.p_EC_peak = std::max(F.p_EC_peak, s[i].p_EC);
    crossing(s, P.stroke - 1e-4, i_reach, F.t_reach, dummy);
    crossing(s, P.stroke, i_contact, F.t_contact, F.v_impact);
    double xm = -1e300;
    for (std::size_t i = i_entry; i < std::min(i_contact, s.size()); ++i) {
        xm = std::max(xm, s[i].x);
        F.rebound_before_contact = std::max(F.rebound_before_contact, xm - s[i].x);
    }
    xm = -1e300;
    for (std::size_t i = i_contact; i < s.size(); ++i) {
        xm = std::max(xm, s[i].x);
        F.rebound_after_contact = std::max(F.rebound_after_contact, xm - s[i].x);
    }
    return F;
}

double max_diff(const std::vector<RigSample>& a, const std::vector<RigSample>& b,
                double RigSample::*m) {
    double d = 0.0;
    const std::size_t n = std::min(a.size(), b.size());
    for (std::size_t i = 0; i < n; ++i) d = std::max(d, std::abs(a[i].*m - b[i].*m));
    return d;
}

}  // namespace

int main(int argc, char** argv) {
    const int n_timing = argc > 1 ? std::max(1, std::atoi(argv[1])) : 20;
    const double p_list[] = {5.0e5, 7.0e5};
    const double z_list[] = {0.1, 1.5, 6.0};

    std::printf("pneumo reference rig (SUNDIALS IDA + KLU, analytic Jacobian), m_load = 3.7 kg, "
                "t_end = 1.2 s, rtol = 1e-6\n");
    std::printf("Jacobian self-check (analytic vs central FD, worst scaled deviation): %.2e\n",
                jacobian_self_check(RigParams{}));
    {
        const RigParams P;
        std::printf("initial x = %.4f mm (static balance against the stop at x = 0)\n\n",
                    initial_position(P) * 1e3);
    }

    std::printf("%-5s %-4s %7s %7s %8s %8s %8s %8s %8s %8s %7s %6s %6s %6s %6s %6s %5s %5s %3s %3s "
                "%8s %8s %8s\n",
                "p_sup", "z_EC", "C_EC", "v_max", "t_entry", "v_entry", "t_zone", "rb_pre",
                "rb_post", "v_imp", "pEC_pk", "TECmin", "@t", "TECmax", "steps", "res", "jac", "etf",
                "ncf", "", "wall_ms", "dx_max", "dpEC_max");
    std::printf("%-5s %-4s %7s %7s %8s %8s %8s %8s %8s %8s %7s %6s %6s %6s %6s %6s %5s %5s %3s %3s "
                "%8s %8s %8s\n",
                "bar", "rev", "dm3/sbar", "m/s", "s", "m/s", "s", "mm", "mm", "m/s", "bar", "degC",
                "s", "degC", "", "", "", "", "", "", "median", "mm", "bar");

    for (double p : p_list) {
        for (double z : z_list) {
            RigParams P;
            P.p_supply = p;
            P.z_EC = z;
            P.m_load = 3.7;

            // figures from a finely sampled run (10 us), same tolerance
            const RigResult fine = simulate(P, 1.2, 1e-6, 1e-5);
            const Figures F = analyse(P, fine.samples);
            // accuracy estimate: same run at rtol = 1e-9
            const RigResult tight = simulate(P, 1.2, 1e-9, 1e-5);
            const double dx = max_diff(fine.samples, tight.samples, &RigSample::x);
            const double dp = max_diff(fine.samples, tight.samples, &RigSample::p_EC);

            // timing at the default output interval
            std::vector<double> ms;
            RigStats st;
            for (int k = 0; k < n_timing; ++k) {
                const auto t0 = std::chrono::steady_clock::now();
                const RigResult r = simulate(P);
                const auto t1 = std::chrono::steady_clock::now();
                ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
                st = r.stats;
            }
            std::nth_element(ms.begin(), ms.begin() + ms.size() / 2, ms.end());
            const double med = ms[ms.size() / 2];

            const double t_zone = F.t_reach - F.t_entry;  // NaN if never reached
            std::printf("%-5.1f %-4.1f %7.3f %7.3f %8.4f %8.3f %8.4f %8.3f %8.3f %8.3f %7.2f "
                        "%6.1f %6.3f %6.1f %6ld %6ld %5ld %5ld %3ld %3s %8.3f %8.1e %8.1e\n",
                        p / 1e5, z, cushion_throttle_C(P, z), F.v_max, F.t_entry, F.v_entry,
                        t_zone, F.rebound_before_contact * 1e3, F.rebound_after_contact * 1e3,
                        F.v_impact, F.p_EC_peak / 1e5, F.T_EC_min - 273.15, F.t_T_EC_min, F.T_EC_max - 273.15,
                        st.steps, st.residual_evals, st.jacobian_evals, st.error_test_failures,
                        st.nonlinear_conv_failures, "", med, dx * 1e3, dp / 1e5);
            std::fflush(stdout);
        }
    }
    std::printf(
        "\nColumns: t_entry = x crosses stroke - cushion_length; t_zone = time from entry until\n"
        "x >= stroke - 0.1 mm (nan = not reached by t_end); rb_pre = largest backward travel after\n"
        "entry before touching the head (x >= stroke); rb_post = largest backward travel after\n"
        "contact (bounce off the elastic stop); v_imp = v when x first reaches stroke; pEC_pk = max\n"
        "p_EC from cushion entry on; TECmin (@t = when) / TECmax over the whole run;\n"
        "steps/res/jac/etf/ncf = IDA statistics of one run; wall_ms = median of %d runs\n"
        "(1 ms output); dx_max / dpEC_max = max deviation from an rtol = 1e-9 run (10 us grid).\n",
        n_timing);
    return 0;
}
