// Virtual point lights (Keller 1997, as Barczak 2006 §4.1 uses them): oriented point lights at the
// diffuse vertices of light paths, each re-emitting its reflected flux over its hemisphere. Two
// sources: the stored hits of the selective photon tracer's QMC groups (Larsen ch. 9), so the set
// follows scene edits through group invalidation (Barczak's §6.3 future work), and the thesis's
// static cosine random walks.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "cpu/photon_map.h"
#include "cpu/ray_tracer.h"
#include "shared/scene.h"
#include "shared/vpl.h"

namespace ag::cpu {

// The VPLs of one photon group: every stored hit of its first `photons` photons (all of them if
// there are fewer), with power Φ_hit · ρ · P/photons so that the VPLs of the whole group carry
// the group's reflected flux in expectation. Nothing if the group holds no traced paths.
void group_vpls(const Scene& scene, const PhotonMaps& maps, int light, int group, int photons,
                std::vector<Vpl>& out);

// The thesis's indirect samples (§4.1): `paths` cosine random walks from each enabled light,
// a VPL at each of the first `bounces` diffuse front-side hits, carrying power × albedo / paths
// (no Russian roulette); mirrors and glass pass the walk on without a VPL. Halton points
// scrambled by `seed`; VPL `group` holds the path index. Deterministic.
std::vector<Vpl> random_walk_vpls(const Scene& scene, const RayTracer& rays, int paths, int bounces,
                                  uint32_t seed);

// Σ power over `vpls` (bookkeeping checks).
glm::dvec3 total_power(const std::vector<Vpl>& vpls);

}  // namespace ag::cpu
