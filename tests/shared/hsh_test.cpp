// Hemispherical harmonics (Gautron 2006 ch. 3): orthonormal over the hemisphere (to 1e-6), and
// holding more of a Phong cos⁵ lobe than SH of the same order (Fig. 3.9, accuracy eq. 3.32).
#include "shared/hsh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace ag {

TEST(Hsh, LegendreMatchesClosedForms) {
    const double x = 0.3;
    EXPECT_NEAR(associated_legendre(2, 0, x), 0.5 * (3 * x * x - 1), 1e-12);
    EXPECT_NEAR(associated_legendre(1, 1, x), -std::sqrt(1 - x * x), 1e-12);
    EXPECT_NEAR(associated_legendre(2, 2, x), 3 * (1 - x * x), 1e-12);
    EXPECT_NEAR(associated_legendre(3, 1, x), -1.5 * (5 * x * x - 1) * std::sqrt(1 - x * x), 1e-12);
}

TEST(Hsh, OrthonormalOverTheHemisphere) {
    const int order = 6;
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m) {
            const std::vector<double> c =
                project_hemisphere([&](double t, double p) { return hsh(l, m, t, p); }, hsh, order);
            for (int l2 = 0; l2 < order; ++l2)
                for (int m2 = -l2; m2 <= l2; ++m2)
                    EXPECT_NEAR(c[size_t(harmonic_index(l2, m2))], l == l2 && m == m2 ? 1.0 : 0.0,
                                1e-6)
                        << "<H" << l << m << ", H" << l2 << m2 << ">";
        }
    // SH are not orthonormal over the hemisphere alone: ⟨Y00, Y00⟩ = ½ there.
    const std::vector<double> y =
        project_hemisphere([](double t, double p) { return sh(0, 0, t, p); }, sh, 1);
    EXPECT_NEAR(y[0], 0.5, 1e-9);
}

// Eq. 3.32: the share of ∫f² the first n² coefficients hold, for a Phong lobe cos⁵ α about a
// direction 30° off the normal (cut at the horizon).
TEST(Hsh, HoldsMoreOfAPhongLobeThanShOfTheSameOrder) {
    const double tilt = std::numbers::pi / 6.0;
    const HemisphereFunction lobe = [&](double t, double p) {
        const double c = std::sin(t) * std::cos(p) * std::sin(tilt) + std::cos(t) * std::cos(tilt);
        return c > 0.0 ? std::pow(c, 5.0) : 0.0;
    };
    const double total = hemisphere_energy(lobe);
    for (int order : {2, 3, 4, 5}) {
        auto held = [&](Basis b) {
            double s = 0.0;
            for (double v : project_hemisphere(lobe, b, order)) s += v * v;
            return s / total;
        };
        const double h = held(hsh), s = held(sh);
        EXPECT_GT(h, s) << "order " << order;
        EXPECT_LE(h, 1.0 + 1e-9);
    }
}

}  // namespace ag
