// Hemispherical harmonics (Gautron 2006 ch. 3, eq. 3.15-3.19) beside real spherical harmonics
// (eq. 3.7-3.8): the associated Legendre polynomials shifted from [−1, 1] to [0, 1] (x → 2x − 1),
// evaluated at cos θ, orthonormal over the upper hemisphere. Order n holds l < n, n² functions,
// indexed l(l + 1) + m. For glossy records (radiance caching) and their tests.
#pragma once

#include <functional>
#include <vector>

namespace ag {

// Associated Legendre P_l^m(x), m ≥ 0, by the recurrences 3.4-3.6 (Condon-Shortley phase).
double associated_legendre(int l, int m, double x);

// Real SH Y_l^m(θ, φ) over the sphere (eq. 3.7, 3.8) and HSH H_l^m(θ, φ) over the upper
// hemisphere θ ≤ π/2 (eq. 3.18, 3.19: K̃ with 2π for 4π, P̃_l^m(cos θ) = P_l^m(2 cos θ − 1)).
double sh(int l, int m, double theta, double phi);
double hsh(int l, int m, double theta, double phi);

inline int harmonic_index(int l, int m) { return l * (l + 1) + m; }

// Projection of f(θ, φ), defined on the upper hemisphere, onto the first order² functions of
// `basis` (sh or hsh; f counts as 0 below the horizon for SH), by Gauss-Legendre quadrature in
// cos θ and the midpoint rule in φ (exact for these bases' products at the sizes used).
using HemisphereFunction = std::function<double(double theta, double phi)>;
using Basis = double (*)(int, int, double, double);
std::vector<double> project_hemisphere(const HemisphereFunction& f, Basis basis, int order,
                                       int nodes = 64, int phi_steps = 128);
// ∫ f² over the upper hemisphere (the denominator of eq. 3.32) by the same quadrature.
double hemisphere_energy(const HemisphereFunction& f, int nodes = 64, int phi_steps = 128);

}  // namespace ag
