// Sun, spot and mesh lights in the CPU tracers (docs/scene-format.md "Lights", "Mesh lights"):
// their photons carry the flux their geometry says, and next-event estimation gives the
// analytic irradiance.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cpu/photon_tracer.h"
#include "cpu/ray_tracer.h"
#include "cpu/reference/reference.h"
#include "cpu/sampling.h"
#include "shared/charts.h"
#include "shared/scene_edit.h"
#include "shared/shapes.h"

namespace ag::cpu {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// A square floor of side 2·half (normal +y) and one light; surfaces and atlas made.
Scene floor_with(const Light& light, float half = 1.0f) {
    Scene s;
    s.path = "floor_with_light";
    Object floor;
    floor.name = "floor";
    floor.mesh = make_quad(2.0f * half, 2.0f * half);
    floor.material.albedo = glm::vec3(0.0f);  // absorb: only first hits
    s.objects.push_back(floor);
    s.lights.push_back(light);
    s.settings.photons.groups = 64;
    s.settings.photons.photons_per_group = 64;
    s.settings.lightmap.texel_size = 0.5f;
    init_versions(s);
    update_sun_discs(s);
    make_surfaces_and_atlas(s);
    return s;
}

// Flux of every photon's first stored hit on the floor.
glm::vec3 first_hit_flux(const Scene& scene) {
    const RayTracer rays(scene);
    const PhotonTracer tracer(scene, rays);
    glm::vec3 sum(0.0f);
    std::vector<TracedVertex> path;
    for (int g = 0; g < scene.settings.photons.groups; ++g)
        for (int i = 0; i < scene.settings.photons.photons_per_group; ++i) {
            path.clear();
            tracer.trace(0, g, i, path);
            if (!path.empty() && path[0].stored) sum += path[0].power;
        }
    return sum;
}

Light sun(const glm::vec3& direction, float irradiance) {
    Light l;
    l.name = "sun";
    l.type = LightType::sun;
    l.direction = glm::normalize(direction);
    l.irradiance = glm::vec3(irradiance);
    return l;
}

TEST(Lights, SunPhotonsDeliverIrradianceTimesProjectedArea) {
    const glm::vec3 dir = glm::normalize(glm::vec3(0.5f, -1.0f, 0.0f));
    const Scene scene = floor_with(sun(dir, 3.0f));
    const float cos_t = -dir.y, area = 4.0f;
    EXPECT_NEAR(first_hit_flux(scene).x / (3.0f * area * cos_t), 1.0f, 0.03f);
}

TEST(Lights, SunDirectIrradianceIsECosineUnlessShadowed) {
    const glm::vec3 dir = glm::normalize(glm::vec3(0.5f, -1.0f, 0.0f));
    Scene scene = floor_with(sun(dir, 3.0f));
    {
        const RayTracer rays(scene);
        const glm::vec3 e =
            direct_irradiance(scene, rays, glm::vec3(0.2f, 0, 0.1f), glm::vec3(0, 1, 0), 1, 0, 0);
        EXPECT_NEAR(e.x, 3.0f * -dir.y, 1e-4f);
    }
    Object roof;  // a roof high above, in the sun's way
    roof.name = "roof";
    roof.mesh = make_box(glm::vec3(0.5f, 0.05f, 0.5f));
    roof.transform.translation = glm::vec3(3.0f * dir.x / dir.y, 3.0f, 0.0f);
    scene.objects.push_back(roof);
    const RayTracer rays(scene);
    const glm::vec3 e =
        direct_irradiance(scene, rays, glm::vec3(0.0f, 0, 0.0f), glm::vec3(0, 1, 0), 1, 0, 0);
    EXPECT_EQ(e.x, 0.0f);
}

Light spot(float inner, float outer) {
    Light l;
    l.name = "spot";
    l.type = LightType::spot;
    l.position = glm::vec3(0.0f, 1.0f, 0.0f);
    l.direction = glm::vec3(0.0f, -1.0f, 0.0f);
    l.intensity = glm::vec3(2.0f);
    l.cone_inner = inner;
    l.cone_outer = outer;
    return l;
}

TEST(Lights, SpotFalloffIsLinearInCosineBetweenItsCones) {
    const Light l = spot(20.0f, 40.0f);
    EXPECT_EQ(l.spot_factor(1.0f), 1.0f);
    EXPECT_EQ(l.spot_factor(std::cos(glm::radians(41.0f))), 0.0f);
    const float ci = std::cos(glm::radians(20.0f)), co = std::cos(glm::radians(40.0f));
    EXPECT_NEAR(l.spot_factor(0.5f * (ci + co)), 0.5f, 1e-5f);
    // Φ = ∫ I f dω over the sphere, by midpoint quadrature in cosθ.
    double phi = 0.0;
    constexpr int kSteps = 20000;
    for (int k = 0; k < kSteps; ++k) {
        const double c = -1.0 + 2.0 * (k + 0.5) / kSteps;
        phi += 2.0 * std::numbers::pi * l.spot_factor(float(c)) * (2.0 / kSteps);
    }
    EXPECT_NEAR(l.power().x / (2.0 * phi), 1.0, 1e-3);
}

TEST(Lights, SpotPhotonsAndNextEventAgreeWithItsIntensity) {
    // Floor 1 below; a 30° cone reaches radius tan 30° = 0.577 < 1: all its flux lands.
    const Scene scene = floor_with(spot(15.0f, 30.0f), 1.0f);
    EXPECT_NEAR(first_hit_flux(scene).x / scene.lights[0].power().x, 1.0f, 0.01f);
    const RayTracer rays(scene);
    const glm::vec3 up(0, 1, 0);
    // (The shadow ray starts ε above the floor, so d is a hair short of 1.)
    EXPECT_NEAR(direct_irradiance(scene, rays, glm::vec3(0), up, 1, 0, 0).x, 2.0f, 1e-3f);
    EXPECT_EQ(direct_irradiance(scene, rays, glm::vec3(0.9f, 0, 0), up, 1, 0, 0).x, 0.0f);
    const glm::vec3 mid(std::tan(glm::radians(22.5f)), 0, 0);
    const float d2 = 1.0f + mid.x * mid.x, c = 1.0f / std::sqrt(d2);
    EXPECT_NEAR(direct_irradiance(scene, rays, mid, up, 1, 0, 0).x,
                2.0f * scene.lights[0].spot_factor(c) * c / d2, 1e-3f);
}

// An emissive square facing down above the floor, as a mesh light, and the same square as a
// quad light: the same flux and the same irradiance.
TEST(Lights, MeshLightMatchesTheQuadLightOfItsShape) {
    Scene mesh_scene = floor_with(Light{}, 2.0f);
    mesh_scene.lights.clear();
    Object lamp;
    lamp.name = "lamp";
    lamp.mesh = make_quad(0.5f, 0.5f);
    for (glm::uvec3& t : lamp.mesh.triangles) std::swap(t.y, t.z);  // face down
    lamp.transform.translation = glm::vec3(0.0f, 1.0f, 0.0f);
    lamp.material.emission = glm::vec3(4.0f);
    mesh_scene.objects.push_back(lamp);
    add_mesh_lights(mesh_scene);
    init_versions(mesh_scene);
    make_surfaces_and_atlas(mesh_scene);
    ASSERT_EQ(mesh_scene.lights.size(), 1u);
    const Light& ml = mesh_scene.lights[0];
    EXPECT_NEAR(ml.power().x, kPi * 4.0f * 0.25f, 1e-4f);

    Light quad;
    quad.name = "quad";
    quad.type = LightType::quad;
    quad.radiance = glm::vec3(4.0f);
    quad.corners = {glm::vec3(-0.25f, 1, -0.25f), glm::vec3(0.25f, 1, -0.25f),
                    glm::vec3(0.25f, 1, 0.25f), glm::vec3(-0.25f, 1, 0.25f)};
    ASSERT_LT(quad.quad_normal().y, 0.0f);
    const Scene quad_scene = floor_with(quad, 2.0f);

    const RayTracer mesh_rays(mesh_scene), quad_rays(quad_scene);
    for (const glm::vec3 p : {glm::vec3(0), glm::vec3(0.7f, 0, 0.3f), glm::vec3(-1.5f, 0, 1)}) {
        const glm::vec3 em =
            direct_irradiance(mesh_scene, mesh_rays, p, glm::vec3(0, 1, 0), 4096, 0.3f, 0.7f);
        const glm::vec3 eq =
            direct_irradiance(quad_scene, quad_rays, p, glm::vec3(0, 1, 0), 4096, 0.3f, 0.7f);
        EXPECT_NEAR(em.x / eq.x, 1.0f, 0.01f) << p.x;
    }
    // Photons: the floor (4×4, the lamp 1 above) catches most of the flux, as with the quad.
    EXPECT_NEAR(first_hit_flux(mesh_scene).x / first_hit_flux(quad_scene).x, 1.0f, 0.02f);
}

}  // namespace
}  // namespace ag::cpu
