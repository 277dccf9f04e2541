// Our flat BVH walked by a compute shader hits what Embree hits: 100k random rays through the
// Cornell box with a 20k-triangle height field and a rotated sphere, same triangle and distance
// within 1e-5 relative. Lives here because it links both sides (tests/boundaries.sh).
#include "gpu/gpu_bvh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../gpu/gl_fixture.h"
#include "cpu/ray_tracer.h"
#include "shared/flat_bvh.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/shapes.h"

namespace ag {

namespace {

Scene bvh_scene() {
    Scene scene = load_scene(AG_SOURCE_DIR "/scenes/cornell.json");
    const Bounds b = scene.world_bounds();
    const glm::vec3 size = b.extent();
    Object plane;
    plane.name = "bumps";
    plane.mesh = make_bumpy_plane(0.8f * size.x, 0.8f * size.z, 100, 0.05f * size.y, 4);
    plane.transform.translation = b.center() + glm::vec3(0.0f, -0.3f * size.y, 0.0f);
    scene.objects.push_back(plane);
    Object ball;
    ball.name = "ball";
    ball.mesh = make_sphere(0.15f * size.x, 3);
    ball.transform.translation = b.center() + glm::vec3(0.1f * size.x, 0.2f * size.y, 0.0f);
    ball.transform.rotation = glm::angleAxis(0.7f, glm::normalize(glm::vec3(1.0f, 2.0f, 3.0f)));
    scene.objects.push_back(ball);
    init_versions(scene);
    return scene;
}

// Whether p lies on triangle `t` of object `o` (as placed), within `tolerance` of its plane and
// of its edges.
bool on_triangle(const Scene& scene, uint32_t o, uint32_t t, const glm::vec3& p, float tolerance) {
    const Object& obj = scene.objects[o];
    const glm::mat4 m = obj.transform.matrix();
    glm::vec3 v[3];
    for (int k = 0; k < 3; ++k)
        v[k] = glm::vec3(m * glm::vec4(obj.mesh.positions[obj.mesh.triangles[t][k]], 1.0f));
    const glm::vec3 n = glm::normalize(glm::cross(v[1] - v[0], v[2] - v[0]));
    if (std::abs(glm::dot(p - v[0], n)) > tolerance) return false;
    for (int k = 0; k < 3; ++k)  // inside every edge's half-plane, up to the tolerance
        if (glm::dot(glm::cross(v[(k + 1) % 3] - v[k], p - v[k]), n) <
            -tolerance * glm::length(v[(k + 1) % 3] - v[k]))
            return false;
    return true;
}

}  // namespace

class GpuBvhTest : public test::GlTest {};

TEST_F(GpuBvhTest, HitsEqualEmbreesOnRandomRays) {
    const Scene scene = bvh_scene();
    const FlatBvh bvh = build_flat_bvh(scene);
    size_t triangles = 0;
    for (const Object& o : scene.objects) triangles += o.mesh.triangles.size();
    ASSERT_EQ(bvh.triangles.size(), triangles);
    EXPECT_GT(triangles, 20000u);
    EXPECT_LE(bvh.depth, kBvhMaxDepth);
    cpu::RayTracer embree(scene);
    gpu::GpuBvh gpu_bvh;
    gpu_bvh.upload(bvh);

    const Bounds b = scene.world_bounds();
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const int n = 100000;
    std::vector<gpu::GpuBvh::Ray> rays(n);
    for (auto& r : rays) {
        // Origins in a box a little larger than the scene; directions uniform.
        r.origin =
            b.min - 0.1f * b.extent() + 1.2f * b.extent() * glm::vec3(u(rng), u(rng), u(rng));
        const float z = 2.0f * u(rng) - 1.0f, a = 6.2831853f * u(rng);
        const float s = std::sqrt(1.0f - z * z);
        r.direction = {s * std::cos(a), s * std::sin(a), z};
        r.tmin = 0.0f;
        r.tmax = 1e30f;
    }
    const std::vector<BvhHit> gpu_hits = gpu_bvh.trace(rays);
    int hits = 0, ties = 0;
    double worst = 0.0;
    const float scale = glm::max(glm::abs(b.min), glm::abs(b.max))[0] +
                        glm::max(glm::abs(b.min), glm::abs(b.max))[1] +
                        glm::max(glm::abs(b.min), glm::abs(b.max))[2];
    for (int i = 0; i < n; ++i) {
        const cpu::RayHit e = embree.intersect({rays[size_t(i)].origin, rays[size_t(i)].direction});
        const BvhHit& g = gpu_hits[size_t(i)];
        const BvhHit c =
            intersect(bvh, rays[size_t(i)].origin, rays[size_t(i)].direction, 0.0f, 1e30f);
        ASSERT_EQ(g.hit, e.hit) << "ray " << i << " embree t " << e.t << " gpu t " << g.t;
        ASSERT_EQ(c.hit, e.hit) << "ray " << i;
        if (!e.hit) continue;
        ++hits;
        // 1e-5 relative, plus on short rays the float rounding of coordinates of `scale` (~1
        // ulp); both measured across the surface, so divided by |cos θ| for grazing rays (where a
        // rounding of the plane's offset moves the hit far along the ray).
        const float cos_theta =
            std::abs(glm::dot(e.normal, glm::normalize(rays[size_t(i)].direction)));
        const float tolerance = (1e-5f * e.t + 1e-7f * scale) / std::max(cos_theta, 1e-3f);
        ASSERT_NEAR(g.t, e.t, tolerance) << "ray " << i << " cos " << cos_theta;
        ASSERT_NEAR(c.t, e.t, tolerance) << "ray " << i << " cos " << cos_theta;
        if (cos_theta > 0.1f && e.t > 0.01f * scale)
            worst = std::max(worst, double(std::abs(g.t - e.t) / e.t));
        // A different triangle only where Embree's hit point lies on ours too: an edge two
        // triangles share, or coplanar faces (the cube's base on the floor).
        if (int(g.object) != e.object || int(g.triangle) != e.triangle) {
            ++ties;
            ASSERT_TRUE(on_triangle(scene, g.object, g.triangle, e.position, 1e-7f * scale))
                << "ray " << i << ": " << g.object << "/" << g.triangle << " vs " << e.object << "/"
                << e.triangle;
        }
    }
    EXPECT_GT(hits, n / 2);
    std::printf(
        "%d of %d rays hit; %d ties (shared edges, coplanar faces); largest relative "
        "distance difference %.2g (|cos| > 0.1, t > 1%% of the scene); BVH %zu nodes, depth %d\n",
        hits, n, ties, worst, bvh.nodes.size(), bvh.depth);
}

TEST_F(GpuBvhTest, EmptySceneHasNoHits) {
    Scene scene;
    const FlatBvh bvh = build_flat_bvh(scene);
    EXPECT_TRUE(bvh.nodes.empty());
    gpu::GpuBvh gpu_bvh;
    gpu_bvh.upload(bvh);
    const auto hits = gpu_bvh.trace({gpu::GpuBvh::Ray{}});
    ASSERT_EQ(hits.size(), 1u);
    EXPECT_FALSE(hits[0].hit);
}

}  // namespace ag
