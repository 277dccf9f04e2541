#include "cpu/ray_tracer.h"

#include <embree3/rtcore.h>

#include <atomic>
#include <glm/gtc/type_ptr.hpp>
#include <stdexcept>
#include <string>

namespace ag::cpu {

namespace {

// RAII handles for Embree objects.
struct DeviceDeleter {
    void operator()(RTCDeviceTy* d) const { rtcReleaseDevice(d); }
};
struct SceneDeleter {
    void operator()(RTCSceneTy* s) const { rtcReleaseScene(s); }
};
using DevicePtr = std::unique_ptr<RTCDeviceTy, DeviceDeleter>;
using ScenePtr = std::unique_ptr<RTCSceneTy, SceneDeleter>;

void check(RTCDevice device, const char* what) {
    const RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE)
        throw std::runtime_error(std::string("Embree error ") + std::to_string(int(e)) + " in " +
                                 what);
}

// Attaches `mesh` as a triangle geometry with the given vertex transform; returns the geomID.
unsigned attach_mesh(RTCDevice device, RTCScene scene, const Mesh& mesh,
                     const Transform* transform) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.positions.size()));
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const glm::vec3 p =
            transform ? transform->apply_point(mesh.positions[i]) : mesh.positions[i];
        v[3 * i] = p.x, v[3 * i + 1] = p.y, v[3 * i + 2] = p.z;
    }
    auto* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                mesh.triangles.size()));
    for (size_t i = 0; i < mesh.triangles.size(); ++i)
        idx[3 * i] = mesh.triangles[i].x, idx[3 * i + 1] = mesh.triangles[i].y,
                idx[3 * i + 2] = mesh.triangles[i].z;
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    return id;
}

void set_instance_transform(RTCGeometry instance, const Transform& t) {
    const glm::mat4 m = t.matrix();  // column-major, as RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR
    rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, glm::value_ptr(m));
    rtcCommitGeometry(instance);
}

}  // namespace

struct RayTracer::Impl {
    DevicePtr device;
    ScenePtr top;                         // static-scene instance + one instance per dynamic object
    ScenePtr static_scene;                // all static objects, world space
    std::vector<ScenePtr> object_scenes;  // per dynamic object, object space (null for static)
    std::vector<int> static_geom_object;  // static geomID -> object index
    std::vector<int> instance_object;     // top-level instID -> object index (-1 = static scene)
    std::vector<unsigned> object_instance;  // object -> top-level instID (dynamic only)
    std::vector<Transform> transforms;      // per object, as last built
    mutable std::atomic<uint64_t> rays{0};

    void build_static(const Scene& scene) {
        static_scene.reset(rtcNewScene(device.get()));
        rtcSetSceneBuildQuality(static_scene.get(), RTC_BUILD_QUALITY_HIGH);
        static_geom_object.clear();
        for (size_t i = 0; i < scene.objects.size(); ++i) {
            const Object& o = scene.objects[i];
            if (o.dynamic) continue;
            const unsigned id = attach_mesh(device.get(), static_scene.get(), o.mesh, &o.transform);
            if (static_geom_object.size() <= id) static_geom_object.resize(id + 1, -1);
            static_geom_object[id] = int(i);
        }
        rtcCommitScene(static_scene.get());
        check(device.get(), "static BVH build");
    }

    void build_top(const Scene& scene) {
        top.reset(rtcNewScene(device.get()));
        rtcSetSceneFlags(top.get(), RTC_SCENE_FLAG_DYNAMIC);
        instance_object.clear();
        object_instance.assign(scene.objects.size(), RTC_INVALID_GEOMETRY_ID);
        auto add_instance = [&](RTCScene child, int object, const Transform& t) {
            RTCGeometry inst = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(inst, child);
            rtcSetGeometryTimeStepCount(inst, 1);
            set_instance_transform(inst, t);
            const unsigned id = rtcAttachGeometry(top.get(), inst);
            rtcReleaseGeometry(inst);
            if (instance_object.size() <= id) instance_object.resize(id + 1, -1);
            instance_object[id] = object;
            return id;
        };
        add_instance(static_scene.get(), -1, Transform{});
        for (size_t i = 0; i < scene.objects.size(); ++i)
            if (scene.objects[i].dynamic)
                object_instance[i] =
                    add_instance(object_scenes[i].get(), int(i), scene.objects[i].transform);
        rtcCommitScene(top.get());
        check(device.get(), "top-level BVH build");
    }
};

RayTracer::RayTracer(const Scene& scene) : impl_(std::make_unique<Impl>()) {
    impl_->device.reset(rtcNewDevice(nullptr));
    if (!impl_->device) throw std::runtime_error("cannot create an Embree device");
    epsilon_ = 1e-5f * scene.diagonal();

    impl_->object_scenes.resize(scene.objects.size());
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        const Object& o = scene.objects[i];
        if (!o.dynamic) continue;
        impl_->object_scenes[i].reset(rtcNewScene(impl_->device.get()));
        rtcSetSceneBuildQuality(impl_->object_scenes[i].get(), RTC_BUILD_QUALITY_HIGH);
        attach_mesh(impl_->device.get(), impl_->object_scenes[i].get(), o.mesh, nullptr);
        rtcCommitScene(impl_->object_scenes[i].get());
    }
    impl_->build_static(scene);
    impl_->build_top(scene);
    impl_->transforms.resize(scene.objects.size());
    for (size_t i = 0; i < scene.objects.size(); ++i)
        impl_->transforms[i] = scene.objects[i].transform;
}

RayTracer::~RayTracer() = default;

bool RayTracer::update(const Scene& scene) {
    bool static_moved = false, dynamic_moved = false;
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        const Transform& now = scene.objects[i].transform;
        Transform& was = impl_->transforms[i];
        if (now.translation == was.translation && now.rotation == was.rotation) continue;
        was = now;
        if (!scene.objects[i].dynamic) {
            static_moved = true;
            continue;
        }
        dynamic_moved = true;
        RTCGeometry inst = rtcGetGeometry(impl_->top.get(), impl_->object_instance[i]);
        set_instance_transform(inst, now);
    }
    if (static_moved) {
        impl_->build_static(scene);
        impl_->build_top(scene);
    } else if (dynamic_moved) {
        rtcCommitScene(impl_->top.get());
        check(impl_->device.get(), "top-level commit");
    }
    return static_moved || dynamic_moved;
}

RayHit RayTracer::intersect(const Ray& ray) const {
    impl_->rays.fetch_add(1, std::memory_order_relaxed);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray.org_x = ray.origin.x, rh.ray.org_y = ray.origin.y, rh.ray.org_z = ray.origin.z;
    rh.ray.dir_x = ray.direction.x, rh.ray.dir_y = ray.direction.y, rh.ray.dir_z = ray.direction.z;
    rh.ray.tnear = ray.tmin;
    rh.ray.tfar = ray.tmax;
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->top.get(), &context, &rh);

    RayHit hit;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
    hit.hit = true;
    hit.t = rh.ray.tfar;
    hit.triangle = int(rh.hit.primID);
    hit.barycentric = {rh.hit.u, rh.hit.v};
    const int inst_object = impl_->instance_object[rh.hit.instID[0]];
    hit.object = inst_object >= 0 ? inst_object : impl_->static_geom_object[rh.hit.geomID];
    hit.position = ray.origin + hit.t * ray.direction;
    // Embree's Ng = (v1 - v0) × (v2 - v0), our counter-clockwise front; for instances it is in the
    // instance's object space, so rotate it into the world.
    glm::vec3 n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    if (inst_object >= 0) n = impl_->transforms[size_t(inst_object)].apply_vector(n);
    hit.normal = glm::normalize(n);
    return hit;
}

bool RayTracer::occluded(const Ray& ray) const {
    impl_->rays.fetch_add(1, std::memory_order_relaxed);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay r;
    r.org_x = ray.origin.x, r.org_y = ray.origin.y, r.org_z = ray.origin.z;
    r.dir_x = ray.direction.x, r.dir_y = ray.direction.y, r.dir_z = ray.direction.z;
    r.tnear = ray.tmin;
    r.tfar = ray.tmax;
    r.time = 0.0f;
    r.mask = 0xFFFFFFFFu;
    r.id = 0;
    r.flags = 0;
    rtcOccluded1(impl_->top.get(), &context, &r);
    return r.tfar < 0.0f;  // Embree sets tfar = -inf on a hit
}

uint64_t RayTracer::rays_cast() const { return impl_->rays.load(std::memory_order_relaxed); }

}  // namespace ag::cpu
