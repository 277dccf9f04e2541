#include "cpu/media_tracking.h"

#include <algorithm>
#include <cmath>

namespace ag::cpu {

namespace {

constexpr int kMaxSpans = 64;  // world media a ray may cross (more are ignored beyond it)

}  // namespace

bool has_media(const Scene& scene) {
    if (!scene.media.empty()) return true;
    return std::any_of(scene.objects.begin(), scene.objects.end(),
                       [](const Object& o) { return o.material.has_interior; });
}

MediaTracker::MediaTracker(const Scene& scene) : scene_(scene), empty_(!has_media(scene)) {
    interiors_.reserve(scene.objects.size());
    for (const Object& o : scene.objects)
        interiors_.push_back(o.material.type == MaterialType::glass && o.material.has_interior
                                 ? &o.material.interior
                                 : nullptr);
}

const Medium* MediaTracker::interior(int object) const {
    return object >= 0 && size_t(object) < interiors_.size() ? interiors_[size_t(object)] : nullptr;
}

int MediaTracker::spans(const Ray& ray, float tmax, int inside, Span* out) const {
    if (inside >= 0) {
        // Glass displaces the world's media: inside it only its own medium counts.
        const Medium* m = interior(inside);
        if (m == nullptr || !(tmax > 0.0f)) return 0;
        out[0] = {0.0f, tmax, m};
        return 1;
    }
    int n = 0;
    for (const Medium& m : scene_.media) {
        float enter = 0.0f, exit = 0.0f;
        if (!ray_box(m.bounds, ray.origin, ray.direction, 0.0f, tmax, enter, exit)) continue;
        if (n == kMaxSpans) break;
        out[n++] = {enter, exit, &m};
    }
    std::sort(out, out + n, [](const Span& a, const Span& b) { return a.enter < b.enter; });
    return n;
}

std::optional<MediumCollision> MediaTracker::sample_collision(const Ray& ray, float tmax,
                                                              int inside, float u,
                                                              HashedStream& more) const {
    Span span[kMaxSpans];
    const int n = spans(ray, tmax, inside, span);
    bool first = true;
    for (int i = 0; i < n; ++i) {
        const Medium& m = *span[i].medium;
        const float majorant = m.majorant();
        if (!(majorant > 0.0f)) continue;
        // Free flight is memoryless, so each span starts afresh at its entry.
        float t = span[i].enter;
        for (;;) {
            const float xi = first ? u : more.next();
            first = false;
            t -= std::log1p(-xi) / majorant;
            if (!(t < span[i].exit)) break;
            // Real with probability σ_t(x)/majorant (always in a homogeneous medium).
            if (m.homogeneous() ||
                more.next() * majorant < m.sigma_t() * m.density(ray.origin + t * ray.direction))
                return MediumCollision{t, &m};
        }
    }
    return std::nullopt;
}

float MediaTracker::transmittance(const Ray& ray, float tmax, int inside,
                                  HashedStream& more) const {
    Span span[kMaxSpans];
    const int n = spans(ray, tmax, inside, span);
    double optical = 0.0;  // homogeneous spans: ∫σ_t in closed form
    float ratio = 1.0f;    // perturbed spans: ratio tracking
    for (int i = 0; i < n; ++i) {
        const Medium& m = *span[i].medium;
        if (m.homogeneous()) {
            optical += double(m.sigma_t()) * double(span[i].exit - span[i].enter);
            continue;
        }
        const float majorant = m.majorant();
        if (!(majorant > 0.0f)) continue;
        for (float t = span[i].enter;;) {
            t -= std::log1p(-more.next()) / majorant;
            if (!(t < span[i].exit)) break;
            ratio *= 1.0f - m.sigma_t() * m.density(ray.origin + t * ray.direction) / majorant;
        }
    }
    return float(std::exp(-optical)) * ratio;
}

}  // namespace ag::cpu
