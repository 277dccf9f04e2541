// The scene graph shared by cpu/ and gpu/: objects, materials, lights, camera, settings, and the
// derived surfaces (Larsen ch. 8) and lightmap atlas. Plain structs, value semantics (yocto-gl).
// All edits go through scene_edit.h so that consumers can update only what an edit touched.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <memory>
#include <string>
#include <vector>

#include "shared/host_device_shared.h"
#include "shared/lightmap.h"
#include "shared/media.h"
#include "shared/mesh.h"
#include "shared/settings.h"
#include "shared/texture.h"

namespace ag {

// Values shared with the frame shaders' `material` uniform (shared/host_device_shared.h).
enum class MaterialType {
    diffuse = kMaterialDiffuse,
    mirror = kMaterialMirror,
    glass = kMaterialGlass
};
inline constexpr std::array kMaterialTypeNames = {"diffuse", "mirror", "glass"};

// A material. Diffuse albedo is the Lambertian reflectance ρ (BRDF ρ/π); mirrors and glass are
// perfectly specular; emission is radiance (W/(sr·m²) in scene units) leaving the surface.
struct Material {
    std::string name;
    MaterialType type = MaterialType::diffuse;
    glm::vec3 albedo{0.75f};
    float ior = 1.5f;
    glm::vec3 emission{0.0f};
    // Emission makes the object a mesh light (Scene::lights gets one for it on load) rather than
    // only a visible lamp; scene files say "light": false for a lamp lit by a separate light.
    bool emits_light = true;
    // Diffuse only: the albedo is `albedo` × this texture at the surface point's texture
    // coordinates (meshes without them use the texture's mean). Shared, read-only.
    std::shared_ptr<const Texture> albedo_map;
    // Glass only (Pfeuti 2009): the medium filling the object, and a Perlin perturbation of its
    // index n(p) = ior + ior_noise(p) (docs/media.md).
    bool has_interior = false;
    Medium interior;
    MediumNoise ior_noise;
};

// Rigid transform: world = rotation * object + translation. Scale is baked into the mesh at load.
struct Transform {
    glm::vec3 translation{0.0f};
    glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // (w, x, y, z)

    glm::mat4 matrix() const;
    glm::vec3 apply_point(const glm::vec3& p) const { return rotation * p + translation; }
    glm::vec3 apply_vector(const glm::vec3& v) const { return rotation * v; }
};

struct Object {
    std::string name;
    Mesh mesh;          // object space, plain indexed arrays
    Material material;  // each object owns its copy, so an albedo edit touches one object
    Transform transform;
    bool dynamic = false;
    std::string source;  // mesh file or built-in shape name, for info/export
};

// The albedo that multiplies an object's texture lookups: the material's, times the texture's
// mean for a textured mesh without texture coordinates (which then has no lookups).
inline glm::vec3 base_albedo(const Object& object) {
    const Material& m = object.material;
    if (!m.albedo_map || m.type != MaterialType::diffuse || object.mesh.has_texcoords())
        return m.albedo;
    return m.albedo * m.albedo_map->mean;
}

// The diffuse albedo at a point of `triangle` (Embree's barycentrics): the material's albedo,
// times its texture there when it has one. Mirrors and glass return their tint.
inline glm::vec3 albedo_at(const Object& object, int triangle, glm::vec2 barycentric) {
    const Material& m = object.material;
    if (!m.albedo_map || m.type != MaterialType::diffuse) return m.albedo;
    if (!object.mesh.has_texcoords() || triangle < 0) return m.albedo * m.albedo_map->mean;
    return m.albedo * m.albedo_map->sample(object.mesh.texcoord(triangle, barycentric));
}

enum class LightType { point, quad, mesh, sun, spot };
inline constexpr std::array kLightTypeNames = {"point", "quad", "mesh", "sun", "spot"};

// Point light: position and intensity I (W/sr, RGB). Quad area light: a parallelogram
// corners[0..3] (corners[2] = corners[1] + corners[3] - corners[0]) emitting radiance L from the
// side its normal (edge01 × edge03) faces. Mesh light: the front faces of an emissive object
// (made by add_mesh_lights, never written in a scene file's "lights"), radiance L = the
// material's emission, moving with its object. Sun: parallel light travelling along `direction`
// with irradiance E (W/unit²) on a surface facing it; its photons leave a disc covering the scene
// (sun_center, sun_radius). Spot: a point light of intensity I on its axis `direction`, full
// inside cone_inner and falling linearly in cosθ to zero at cone_outer (half-angles, degrees).
struct Light {
    std::string name;
    LightType type = LightType::point;
    glm::vec3 position{0.0f};
    glm::vec3 intensity{0.0f};
    std::array<glm::vec3, 4> corners{};
    glm::vec3 radiance{0.0f};
    bool enabled = true;
    // Mesh light: the object, its area and the cumulative area fraction of its triangles (rigid
    // transforms keep both); `position` follows the object's world bounds centre.
    int object = -1;
    float mesh_area = 0.0f;
    std::vector<float> triangle_cdf;
    glm::vec3 direction{0.0f, -1.0f, 0.0f};        // sun, spot: unit direction light travels
    glm::vec3 irradiance{0.0f};                    // sun
    float cone_inner = 30.0f, cone_outer = 45.0f;  // spot, degrees
    glm::vec3 sun_center{0.0f};                    // sun: the disc photons leave (update_sun)
    float sun_radius = 0.0f;

    glm::vec3 quad_normal() const;  // unit normal of a quad light
    float quad_area() const;
    bool is_area() const { return type == LightType::quad || type == LightType::mesh; }
    float area() const;        // emitting area of a quad or mesh light
    glm::vec3 center() const;  // position (mesh: its object's centre), or the quad's centre
    glm::vec3 power() const;   // emitted flux Φ (W): 4πI for a point, πLA for a quad or mesh
    // Spot falloff at cosθ from the axis: 1 inside the inner cone, linear in cosθ to 0 at the
    // outer one; 1 for every other light.
    float spot_factor(float cos_theta) const;
    float cos_inner() const;
    float cos_outer() const;
    // The value a user sets: intensity I (W/sr) for a point or spot light, irradiance E for a
    // sun, radiance L for an area light.
    const glm::vec3& value() const {
        return type == LightType::point || type == LightType::spot ? intensity
               : type == LightType::sun                            ? irradiance
                                                                   : radiance;
    }
    glm::vec3& value() {
        return type == LightType::point || type == LightType::spot ? intensity
               : type == LightType::sun                            ? irradiance
                                                                   : radiance;
    }
};

// A point on an area light, uniform in area, with the light's front normal there (world space).
struct LightPoint {
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f};
};

struct Camera {
    glm::vec3 eye{0.0f, 0.0f, 1.0f};
    glm::vec3 target{0.0f};
    glm::vec3 up{0.0f, 1.0f, 0.0f};
    float fov_y = 40.0f;  // vertical field of view, degrees
    int width = 512;
    int height = 512;
};

// A surface (Larsen ch. 8): connected triangles of one object whose normals differ by less than
// the crease angle across every shared edge. Each surface owns its photon map and its lightmaps.
struct Surface {
    int object = -1;
    std::vector<int> triangles;  // triangle indices into the object's mesh
    std::vector<int> charts;     // chart ids into Scene::atlas.charts
    float area = 0.0f;           // world area (rigid transforms keep it)
    glm::vec3 normal{0.0f};      // area-weighted mean normal, object space
};

// What an edit changed; consumers keep the last sequence number they saw.
enum class ChangeKind {
    object_transform,
    object_material,
    light_position,  // a point light moved or a quad light's corners changed
    light_power,     // intensity / radiance changed (colour or strength)
    light_enabled,
    camera,
};
inline constexpr std::array kChangeKindNames = {"object_transform", "object_material",
                                                "light_position",   "light_power",
                                                "light_enabled",    "camera"};

struct SceneChange {
    uint64_t sequence = 0;
    ChangeKind kind = ChangeKind::object_transform;
    int index = -1;  // object or light index; -1 for the camera
};

// Where load_scene spent its time, in seconds (afterglow info --timing).
struct LoadTiming {
    double files = 0.0;     // JSON, mesh and model files, shapes, lights
    double surfaces = 0.0;  // crease-angle surfaces and charts, per object
    double packing = 0.0;   // the atlas: charts shelf-packed
    double texels = 0.0;    // texel records
};

// What every scene_edit.h edit calls before it changes anything. The pipeline sets it to wait for
// its photon work in flight, which reads the scene while frames go on (docs/architecture.md "One
// frame": "a frame never waits for photon tracing"). It belongs to the scene object it was set on:
// a copy of the scene (a script's staging copy, a look-ahead copy, a reference run) starts without
// it.
struct EditGuard {
    std::function<void()> wait;
    const void* owner =
        nullptr;  // who set `wait` (a pipeline replaced by another clears only its own)

    EditGuard() = default;
    EditGuard(const EditGuard&) {}
    EditGuard& operator=(const EditGuard&) { return *this; }
    void operator()() const {
        if (wait) wait();
    }
};

struct Scene {
    std::string name;
    std::string path;  // the scene file, for messages and relative paths
    std::string length_unit = "unit";
    std::string script;  // optional Lua edit script (path, resolved against the scene)
    Camera camera;
    std::vector<Object> objects;
    std::vector<Light> lights;
    std::vector<Medium> media;  // participating media in world boxes (disjoint), docs/media.md
    Settings settings;

    // Derived by make_surfaces_and_atlas() (shared/charts.h); rebuilt only if meshes change.
    std::vector<Surface> surfaces;
    std::vector<std::vector<int>> triangle_surface;  // [object][triangle] -> surface id
    LightmapAtlas atlas;
    // Per object, its mesh as loaded where make_surfaces_and_atlas split triangles along a tile
    // cut (lightmap.refine_tile; empty otherwise): the next layout starts again from it.
    std::vector<Mesh> unsplit_meshes;
    LoadTiming load_timing;

    // Versioning: every edit bumps `version` and the touched item's counter and appends a change.
    uint64_t version = 0;
    std::vector<uint64_t> object_versions;  // per object, transform or material edits
    std::vector<uint64_t> light_versions;   // per light
    uint64_t camera_version = 0;
    std::vector<SceneChange> changes;
    EditGuard before_edit;  // set by the Pipeline working on this scene

    int find_object(const std::string& object_name) const;  // -1 if absent
    // World-space bounds of every object as placed now, and their diagonal (1 if empty): the
    // scale for offsets, tolerances and search radii.
    Bounds world_bounds() const;
    float diagonal() const;
    int find_light(const std::string& light_name) const;  // -1 if absent
    size_t triangle_count() const;
};

// Side n of the n×n grid of point lights that stands in for a quad light on the GPU
// (n² ≈ settings.direct.area_light_samples).
int quad_light_grid(const Settings& settings);
// (u, v) ∈ [0,1)² → a point uniform in area on a quad or mesh light. For a mesh, u picks a
// triangle by area and is reused (rescaled) inside it, so stratified (u, v) stay stratified.
LightPoint sample_area_light(const Scene& scene, const Light& light, float u, float v);
// Makes a mesh light for every object whose material emits and `emits_light`, named after the
// object (an InputError naming scene.path if a light of that name exists), and updates their
// positions; call after objects change place (scene_edit does).
void add_mesh_lights(Scene& scene);
void update_mesh_light_positions(Scene& scene, int object);
// Sizes every sun's photon disc to the scene's world bounds now (with a 1% margin); call after
// loading. Objects that later move outside these bounds get no sun photons there.
void update_sun_discs(Scene& scene);
// Per object, the index of the mesh light it is, or -1.
std::vector<int> object_lights(const Scene& scene);
// Point-light samples the GPU frame needs for every light of the scene, enabled or not (an edit
// may turn any of them on): 1 per point, spot or sun light, n² per quad or mesh light.
int light_sample_count(const Scene& scene);
// Throws InputError, naming scene.path, where light_sample_count exceeds kMaxLightSamples: the
// GPU frame holds no more, and dropping lights silently would change the image.
void check_light_samples(const Scene& scene);

// Upper bound on photons traced per load: groups × photons_per_group × lights, and caustic photons
// × lights (docs/scene-format.md). Beyond it the photon arrays alone would need many GiB.
inline constexpr int64_t kMaxScenePhotons = 100'000'000;
// Throws InputError, naming scene.path and the setting, where either product exceeds
// kMaxScenePhotons.
void check_photon_budget(const Scene& scene);

// Tolerances relative to the scene's extent (Scene::diagonal()): the offset every CPU tracer moves
// a ray's origin off its surface (RayTracer::epsilon), and the frame's near clipping plane
// (GBuffer::view_of). A scene whose parts lie far apart (a room and a tile 10^7 away) makes both
// larger than the room: warn_about_scale says so at load.
inline constexpr float kRayOffsetPerDiagonal = 1e-5f;
inline constexpr float kNearPlanePerDiagonal = 1e-3f;
// Warns (one line each) where the scene's extent swamps its parts: geometry nearer the camera than
// the near plane (it is clipped from the frame), and objects smaller than ten ray offsets (the
// tracers step over them). Silent for scenes of one scale.
void warn_about_scale(const Scene& scene);

// Upper bound on the triangles a scene file places, every object's and every model part's
// together (a glTF node tree that places one mesh many times counts each placement). Ten times
// the largest scene here (3 M triangles); beyond it meshes, BVHs, charts and photon records need
// many GiB, and a small glTF whose nodes place one mesh 2^40 times would run out of memory.
inline constexpr int64_t kMaxSceneTriangles = int64_t(1) << 26;

}  // namespace ag
