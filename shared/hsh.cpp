#include "shared/hsh.h"

#include <cmath>
#include <numbers>

namespace ag {

namespace {

double factorial_ratio(int a, int b) {  // a! / b!
    double r = 1.0;
    for (int i = b + 1; i <= a; ++i) r *= i;
    for (int i = a + 1; i <= b; ++i) r /= i;
    return r;
}

// Gauss-Legendre nodes and weights on [0, 1] (Newton on P_n, Golub-Welsch-free).
void gauss_legendre01(int n, std::vector<double>& x, std::vector<double>& w) {
    x.resize(size_t(n));
    w.resize(size_t(n));
    for (int i = 0; i < n; ++i) {
        double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5)), dp = 0.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= n; ++k) {
                const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            const double dz = p1 / dp;
            z -= dz;
            if (std::abs(dz) < 1e-15) break;
        }
        x[size_t(i)] = 0.5 * (z + 1.0);
        w[size_t(i)] = 1.0 / ((1.0 - z * z) * dp * dp);  // 2/((1−z²)P'²) halved for [0, 1]
    }
}

}  // namespace

double associated_legendre(int l, int m, double x) {
    // Eq. 3.5: P_m^m = (−1)^m (2m − 1)!! (1 − x²)^{m/2}.
    double pmm = 1.0;
    const double s = std::sqrt(std::max(0.0, (1.0 - x) * (1.0 + x)));
    for (int i = 1; i <= m; ++i) pmm *= -(2.0 * i - 1.0) * s;
    if (l == m) return pmm;
    double pmm1 = x * (2.0 * m + 1.0) * pmm;  // eq. 3.6
    if (l == m + 1) return pmm1;
    for (int k = m + 2; k <= l; ++k) {  // eq. 3.4
        const double pk = (x * (2.0 * k - 1.0) * pmm1 - (k + m - 1.0) * pmm) / (k - m);
        pmm = pmm1;
        pmm1 = pk;
    }
    return pmm1;
}

double sh(int l, int m, double theta, double phi) {
    const int am = std::abs(m);
    const double k =
        std::sqrt((2.0 * l + 1.0) / (4.0 * std::numbers::pi) * factorial_ratio(l - am, l + am));
    const double p = associated_legendre(l, am, std::cos(theta));
    if (m == 0) return k * p;
    return std::sqrt(2.0) * k * p * (m > 0 ? std::cos(m * phi) : std::sin(-m * phi));
}

double hsh(int l, int m, double theta, double phi) {
    const int am = std::abs(m);
    const double k =
        std::sqrt((2.0 * l + 1.0) / (2.0 * std::numbers::pi) * factorial_ratio(l - am, l + am));
    const double p = associated_legendre(l, am, 2.0 * std::cos(theta) - 1.0);
    if (m == 0) return k * p;
    return std::sqrt(2.0) * k * p * (m > 0 ? std::cos(m * phi) : std::sin(-m * phi));
}

std::vector<double> project_hemisphere(const HemisphereFunction& f, Basis basis, int order,
                                       int nodes, int phi_steps) {
    std::vector<double> x, w;
    gauss_legendre01(nodes, x, w);
    std::vector<double> c(size_t(order) * size_t(order), 0.0);
    const double dphi = 2.0 * std::numbers::pi / phi_steps;
    for (size_t i = 0; i < x.size(); ++i) {
        const double theta = std::acos(x[i]);  // dω = d(cos θ) dφ
        for (int j = 0; j < phi_steps; ++j) {
            const double phi = (j + 0.5) * dphi;
            const double v = f(theta, phi) * w[i] * dphi;
            if (v == 0.0) continue;
            for (int l = 0; l < order; ++l)
                for (int m = -l; m <= l; ++m)
                    c[size_t(harmonic_index(l, m))] += v * basis(l, m, theta, phi);
        }
    }
    return c;
}

double hemisphere_energy(const HemisphereFunction& f, int nodes, int phi_steps) {
    std::vector<double> x, w;
    gauss_legendre01(nodes, x, w);
    const double dphi = 2.0 * std::numbers::pi / phi_steps;
    double e = 0.0;
    for (size_t i = 0; i < x.size(); ++i)
        for (int j = 0; j < phi_steps; ++j) {
            const double v = f(std::acos(x[i]), (j + 0.5) * dphi);
            e += v * v * w[i] * dphi;
        }
    return e;
}

}  // namespace ag
