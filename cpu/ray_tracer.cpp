#include "cpu/ray_tracer.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <glm/gtc/type_ptr.hpp>
#include <stdexcept>
#include <string>

#include "shared/coincident_hits.h"

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

// What the filter keeps of a face for intersect to make its hit (no initialisers, as
// HitCandidate).
struct EmbreeHit {
    float t;
    unsigned inst, geom, prim;
    glm::vec2 uv;
    glm::vec3 ng;  // Embree's unnormalised normal, in the instance's space
};

// One intersect query's state; Embree hands the context (the first member) back to the filter.
struct CoincidentQuery {
    RTCIntersectContext context;
    const std::vector<int>* instance_object;
    const std::vector<int>* static_geom_object;
    float tmax;  // the caller's: the window never reaches past it
    CoincidentHits<EmbreeHit> hits;
};

// Context filter for RayTracer::intersect: Embree reports, among faces at the same distance,
// whichever its traversal meets first (shared/coincident_hits.h says why that is an accident).
// The filter records every face within the window of the nearest and accepts it with tfar moved
// to the window's end, so that Embree keeps culling everything beyond (Embree 3 lets a filter
// move tfar: its epilogs re-test a leaf's remaining hits against it).
void keep_coincident(const RTCFilterFunctionNArguments* args) {
    if (args->valid[0] == 0) return;
    auto* q = reinterpret_cast<CoincidentQuery*>(const_cast<RTCIntersectContext*>(args->context));
    RTCRayN* ray = args->ray;
    RTCHitN* hit = args->hit;
    const unsigned n = args->N;
    EmbreeHit h;
    h.t = RTCRayN_tfar(ray, n, 0);
    h.inst = RTCHitN_instID(hit, n, 0, 0);
    h.geom = RTCHitN_geomID(hit, n, 0);
    h.prim = RTCHitN_primID(hit, n, 0);
    h.uv = {RTCHitN_u(hit, n, 0), RTCHitN_v(hit, n, 0)};
    h.ng = {RTCHitN_Ng_x(hit, n, 0), RTCHitN_Ng_y(hit, n, 0), RTCHitN_Ng_z(hit, n, 0)};
    const int inst_object = (*q->instance_object)[h.inst];
    HitCandidate c;
    c.t = h.t;
    c.object = uint32_t(inst_object >= 0 ? inst_object : (*q->static_geom_object)[h.geom]);
    c.triangle = h.prim;
    // The ray as the face's BVH sees it (an instance's own space, where Ng lives too): the
    // facing and the cosine are the world's, the transforms being rigid.
    set_facing(c, {RTCRayN_dir_x(ray, n, 0), RTCRayN_dir_y(ray, n, 0), RTCRayN_dir_z(ray, n, 0)},
               h.ng);
    q->hits.add(c, h);
    RTCRayN_tfar(ray, n, 0) = std::min(q->tmax, q->hits.cull_t());
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

    // A hit from Embree's IDs, in the world.
    RayHit make_hit(const Ray& ray, float t, unsigned inst, unsigned geom, unsigned prim,
                    glm::vec2 uv, glm::vec3 ng) const;

    void build_static(const Scene& scene) {
        static_scene.reset(rtcNewScene(device.get()));
        rtcSetSceneFlags(static_scene.get(), RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
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
        rtcSetSceneFlags(top.get(),
                         RTC_SCENE_FLAG_DYNAMIC | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
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
    epsilon_ = kRayOffsetPerDiagonal * scene.diagonal();
    coincident_ = coincident_tolerance(scene.diagonal(), glm::vec3(0.0f));

    impl_->object_scenes.resize(scene.objects.size());
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        const Object& o = scene.objects[i];
        if (!o.dynamic) continue;
        impl_->object_scenes[i].reset(rtcNewScene(impl_->device.get()));
        rtcSetSceneFlags(impl_->object_scenes[i].get(), RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
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

namespace {

RTCRayHit embree_ray(const Ray& ray) {
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
    return rh;
}

}  // namespace

RayHit RayTracer::Impl::make_hit(const Ray& ray, float t, unsigned inst, unsigned geom,
                                 unsigned prim, glm::vec2 uv, glm::vec3 ng) const {
    RayHit hit;
    hit.hit = true;
    hit.t = t;
    hit.triangle = int(prim);
    hit.barycentric = uv;
    const int inst_object = instance_object[inst];
    hit.object = inst_object >= 0 ? inst_object : static_geom_object[geom];
    hit.position = ray.origin + hit.t * ray.direction;
    // Embree's Ng = (v1 - v0) × (v2 - v0), our counter-clockwise front; for instances it is in the
    // instance's object space, so rotate it into the world.
    if (inst_object >= 0) ng = transforms[size_t(inst_object)].apply_vector(ng);
    hit.normal = glm::normalize(ng);
    return hit;
}

RayHit RayTracer::intersect(const Ray& ray) const {
    impl_->rays.fetch_add(1, std::memory_order_relaxed);
    CoincidentQuery q{{},
                      &impl_->instance_object,
                      &impl_->static_geom_object,
                      ray.tmax,
                      {std::max(coincident_, coincident_tolerance(0.0f, ray.origin)),
                       glm::length(ray.direction)}};
    rtcInitIntersectContext(&q.context);
    q.context.filter = keep_coincident;
    RTCRayHit rh = embree_ray(ray);
    rtcIntersect1(impl_->top.get(), &q.context, &rh);
    const EmbreeHit* h = q.hits.best();
    if (!h) return {};
    return impl_->make_hit(ray, h->t, h->inst, h->geom, h->prim, h->uv, h->ng);
}

RayHit RayTracer::intersect_unordered(const Ray& ray) const {
    impl_->rays.fetch_add(1, std::memory_order_relaxed);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh = embree_ray(ray);
    rtcIntersect1(impl_->top.get(), &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {};
    return impl_->make_hit(ray, rh.ray.tfar, rh.hit.instID[0], rh.hit.geomID, rh.hit.primID,
                           {rh.hit.u, rh.hit.v}, {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
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
