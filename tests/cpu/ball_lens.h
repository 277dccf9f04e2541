// A ball lens (a glass sphere of index n) focusing a point light onto a plane, answered exactly:
// the true sphere traced in closed form, every Fresnel branch at every interface followed (Larsen
// ch. 12's caustic, checked against geometric optics). Shared by the CPU caustic-photon test and
// the GPU screen-space filter test.
#pragma once

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>
#include <numbers>
#include <utility>
#include <vector>

#include "shared/charts.h"
#include "shared/scene.h"
#include "shared/scene_edit.h"
#include "shared/shapes.h"

namespace ag::test {

struct BallLens {
    double radius = 1.0;
    double ior = 1.5;
    double centre_height = 2.5;  // sphere centre above the plane y = 0
    double light_height = 12.0;  // point light above the plane, on the axis
    double intensity = 1000.0;   // W/sr
    // Paraxial focus behind the centre (thick ball lens, principal planes at the centre):
    // f = nR / 2(n − 1), 1/s' = 1/f − 1/s with s the light's distance from the centre.
    double paraxial_image_distance() const {
        const double f = ior * radius / (2.0 * (ior - 1.0)), s = light_height - centre_height;
        return 1.0 / (1.0 / f - 1.0 / s);
    }
};

// The scene: a plane (albedo ρ, normal +Y) of half-size `half`, the glass sphere as an icosphere
// with `subdivisions`, the point light.
inline Scene ball_lens_scene(const BallLens& lens, int subdivisions, float half = 20.0f,
                             float albedo = 0.5f) {
    Scene s;
    s.path = "ball_lens";
    Object plane;
    plane.name = "plane";
    plane.mesh = make_quad(2.0f * half, 2.0f * half);
    plane.material.albedo = glm::vec3(albedo);
    s.objects.push_back(plane);
    Object ball;
    ball.name = "ball";
    ball.mesh = make_sphere(float(lens.radius), subdivisions);
    ball.material.type = MaterialType::glass;
    ball.material.ior = float(lens.ior);
    ball.transform.translation = {0.0f, float(lens.centre_height), 0.0f};
    ball.dynamic = true;
    s.objects.push_back(ball);
    Light l;
    l.name = "lamp";
    l.position = {0.0f, float(lens.light_height), 0.0f};
    l.intensity = glm::vec3(float(lens.intensity));
    s.lights.push_back(l);
    s.settings.lightmap.texel_size = 4.0f;
    init_versions(s);
    make_surfaces_and_atlas(s);
    return s;
}

// Power landing on the plane at distance `radius` from the axis.
using RadialPower = std::vector<std::pair<double, double>>;

struct CausticSpot {
    double power = 0.0;  // total caustic power on the plane, W
    double r50 = 0.0;    // radius around the axis holding half of it
    double r90 = 0.0;    // and 90%
};

inline CausticSpot spot_of(RadialPower radial) {
    std::sort(radial.begin(), radial.end());
    CausticSpot s;
    for (const auto& rp : radial) s.power += rp.second;
    double acc = 0.0;
    for (const auto& [r, p] : radial) {
        acc += p;
        if (s.r50 == 0.0 && acc >= 0.5 * s.power) s.r50 = r;
        if (acc >= 0.9 * s.power) {
            s.r90 = r;
            break;
        }
    }
    return s;
}

namespace detail {

// Unpolarised Fresnel reflectance, light going from index 1 to index 1/eta... written from the
// textbook (Hecht 4.42–4.43), independent of cpu/sampling.h.
inline double fresnel(double cos_i, double n1, double n2) {
    const double sin_t = n1 / n2 * std::sqrt(std::max(0.0, 1.0 - cos_i * cos_i));
    if (sin_t >= 1.0) return 1.0;
    const double cos_t = std::sqrt(1.0 - sin_t * sin_t);
    const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    const double rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
    return 0.5 * (rs * rs + rp * rp);
}

// Follows a ray (in the x-y plane) through the exact sphere, splitting at every interface.
inline void trace(const BallLens& lens, glm::dvec2 o, glm::dvec2 d, double weight, bool inside,
                  int depth, RadialPower& out) {
    if (weight < 1e-7 || depth > 12) return;
    const glm::dvec2 c(0.0, lens.centre_height);
    const glm::dvec2 oc = o - c;
    const double b = glm::dot(oc, d), cc = glm::dot(oc, oc) - lens.radius * lens.radius;
    const double disc = b * b - cc;
    double t = -1.0;
    if (disc > 0.0) {
        const double q = std::sqrt(disc);
        t = inside ? -b + q : (-b - q > 1e-9 ? -b - q : -1.0);
    }
    if (t <= 1e-9) {
        // Leaves the sphere for good: store where it meets the plane, if it goes down.
        if (depth > 0 && d.y < 0.0) out.emplace_back(std::abs(o.x - o.y / d.y * d.x), weight);
        return;
    }
    const glm::dvec2 p = o + t * d, n = (p - c) / lens.radius;  // outward
    const glm::dvec2 facing = inside ? -n : n;
    const double cos_i = -glm::dot(d, facing);
    const double n1 = inside ? lens.ior : 1.0, n2 = inside ? 1.0 : lens.ior;
    const double f = fresnel(cos_i, n1, n2);
    trace(lens, p, d + 2.0 * cos_i * facing, weight * f, inside, depth + 1, out);
    if (f < 1.0) {
        const double eta = n1 / n2, k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
        const glm::dvec2 refracted = eta * d + (eta * cos_i - std::sqrt(k)) * facing;
        trace(lens, p, glm::normalize(refracted), weight * (1.0 - f), !inside, depth + 1, out);
    }
}

}  // namespace detail

// The exact caustic: the cone of directions from the light onto the sphere, cut into `rings`
// equal solid angles (midpoint rule in 1 − cosθ); by symmetry one ray per ring, carrying
// I·2π·Δ(1 − cosθ).
inline RadialPower exact_caustic(const BallLens& lens, int rings) {
    const double dist = lens.light_height - lens.centre_height;
    const double sin_a = lens.radius / dist, cos_a = std::sqrt(1.0 - sin_a * sin_a);
    const double du = (1.0 - cos_a) / rings;
    RadialPower out;
    for (int i = 0; i < rings; ++i) {
        const double u = (i + 0.5) * du, cos_t = 1.0 - u, sin_t = std::sqrt(u * (2.0 - u));
        const double weight = lens.intensity * 2.0 * std::numbers::pi * du;
        detail::trace(lens, {0.0, lens.light_height}, {sin_t, -cos_t}, weight, false, 0, out);
    }
    return out;
}

// The same for parallel light straight down (a sun of irradiance E): `rings` annuli of equal area
// across the sphere's disc, one ray each carrying E·π R²/rings.
inline RadialPower exact_sun_caustic(const BallLens& lens, double irradiance, int rings) {
    RadialPower out;
    const double start = lens.centre_height + 2.0 * lens.radius;
    for (int i = 0; i < rings; ++i) {
        const double h = lens.radius * std::sqrt((i + 0.5) / rings);
        const double weight = irradiance * std::numbers::pi * lens.radius * lens.radius / rings;
        detail::trace(lens, {h, start}, {0.0, -1.0}, weight, false, 0, out);
    }
    return out;
}

// ball_lens_scene with the point light replaced by a sun of irradiance E shining straight down.
inline Scene sun_ball_lens_scene(const BallLens& lens, int subdivisions, double irradiance) {
    Scene s = ball_lens_scene(lens, subdivisions);
    Light& l = s.lights[0];
    l.name = "sun";
    l.type = LightType::sun;
    l.direction = {0.0f, -1.0f, 0.0f};
    l.irradiance = glm::vec3(float(irradiance));
    update_sun_discs(s);
    return s;
}

}  // namespace ag::test
