// One step of the ray equation through a smoothed index grid (Pfeuti 2009, eqs. 2.10/2.11),
// GLSL shared by the photon march and the view march.
#pragma once

namespace ag::gpu {

// Needs, declared before it: uniforms grid_min and voxel (world size of a voxel), float
// index_at(vec3 g) and vec3 index_gradient(vec3 g) (∇n in world units) at voxel coordinates g.
//
// With τ such that dτ = ds/n, eqs. 2.10/2.11 (dx/ds = v/n, dv/ds = ∇n) read dx/dτ = v,
// dv/dτ = n∇n = ∇(n²/2): a separable Hamiltonian H = |v|²/2 − n²/2, which the leapfrog
// (Störmer–Verlet: half drift, kick at the midpoint, half drift) integrates to second order,
// keeping |v| ≈ n without drift. The first-order Euler step it replaces lost 0.01 of the ball
// lens's focus (1.3% of its focal length) at any resolution with ¼-voxel steps, since its error
// goes with the step over the smoothed interface's width, both a fixed number of voxels.
// x, v = n dx/ds and n (the index at x) advance by a path length of about ds.
inline constexpr const char* kMediaRayStep = R"(
void ray_step(inout vec3 x, inout vec3 v, inout float n, float ds) {
    float h = ds / n;
    vec3 xh = x + 0.5 * h * v;
    vec3 gh = (xh - grid_min) / voxel;
    v += h * index_at(gh) * index_gradient(gh);
    x = xh + 0.5 * h * v;
    n = index_at((x - grid_min) / voxel);
}
)";

}  // namespace ag::gpu
