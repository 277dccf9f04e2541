#include "shared/pipeline/vpl_method.h"

#include <algorithm>
#include <glm/gtc/constants.hpp>
#include <numeric>

#include "gpu/gl.h"
#include "shared/camera.h"
#include "shared/scene_edit.h"

namespace ag {

namespace {
// Random-walk VPLs are grouped this many paths to a slot (a slot is the unit of update).
constexpr int kWalkPathsPerSlot = 25;
}  // namespace

VplMethod::VplMethod(const Scene& scene, int width, int height)
    : scene_(scene),
      width_(width),
      height_(height),
      tw_(std::max(1, width / std::max(1, scene.settings.vpl.resolution_divisor))),
      th_(std::max(1, height / std::max(1, scene.settings.vpl.resolution_divisor))),
      rays_(scene),
      pool_(scene.settings.threads) {
    std::vector<float> zero(size_t(tw_) * size_t(th_) * 4, 0.0f);
    texture_ = gpu::make_float_texture(tw_, th_, false, zero.data());
    gpu::gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    gpu::gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gpu::gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gpu::gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    sum_.assign(size_t(tw_) * size_t(th_), glm::vec3(0.0f));
    if (!scene_.changes.empty()) seen_sequence_ = scene_.changes.back().sequence;
    const VplSettings& vs = scene_.settings.vpl;
    if (vs.source == VplSource::photons) {
        slots_.resize(scene_.lights.size() * size_t(scene_.settings.photons.groups));
    } else {
        // The thesis's static set: traced once, in the scene as it is now.
        const std::vector<Vpl> walk = cpu::random_walk_vpls(scene_, rays_, vs.walk_paths,
                                                            vs.walk_bounces, scene_.settings.seed);
        const int per_light = (vs.walk_paths + kWalkPathsPerSlot - 1) / kWalkPathsPerSlot;
        slots_.resize(scene_.lights.size() * size_t(per_light));
        for (const Vpl& v : walk) {
            Slot& s = slots_[size_t(v.light * per_light + v.group / kWalkPathsPerSlot)];
            s.next.push_back(v);
            s.has_next = true;
        }
        for (Slot& s : slots_)
            if (s.has_next) mark(s, 0);
    }
}

std::vector<size_t> VplMethod::make_points() {
    camera_version_ = scene_.camera_version;
    const std::vector<cpu::SurfacePoint> before = std::move(points_);
    points_.assign(size_t(tw_) * size_t(th_), cpu::SurfacePoint{});
    const Camera& cam = scene_.camera;
    pool_.parallel_for(
        size_t(th_),
        [&](size_t y) {
            for (int x = 0; x < tw_; ++x) {
                const float px = (float(x) + 0.5f) * float(cam.width) / float(tw_);
                const float py = (float(y) + 0.5f) * float(cam.height) / float(th_);
                const glm::vec3 dir = camera_ray_direction(cam, px, py);
                const cpu::RayHit hit = rays_.intersect({cam.eye, dir});
                if (!hit.hit) continue;
                const Material& m = scene_.objects[size_t(hit.object)].material;
                if (m.type != MaterialType::diffuse) continue;  // the frame shades these itself
                cpu::SurfacePoint& p = points_[y * size_t(tw_) + size_t(x)];
                p.position = hit.position;
                p.normal = glm::dot(dir, hit.normal) < 0.0f ? hit.normal : -hit.normal;
            }
        },
        1);
    std::vector<size_t> changed;
    for (size_t i = 0; i < points_.size(); ++i)
        if (before.size() != points_.size() || before[i].position != points_[i].position ||
            before[i].normal != points_[i].normal)
            changed.push_back(i);
    return changed;
}

void VplMethod::reshade_points(const std::vector<size_t>& changed) {
    if (changed.empty()) return;
    std::vector<cpu::SurfacePoint> subset;
    for (size_t i : changed) subset.push_back(points_[i]);
    std::vector<glm::vec3> e(subset.size());
    for (Slot& s : slots_) {
        if (s.e.empty()) continue;
        std::fill(e.begin(), e.end(), glm::vec3(0.0f));
        if (!s.shown.empty())
            cpu::add_vpl_irradiance(rays_, subset, s.shown.data(), s.shown.size(),
                                    scene_.settings.vpl.clamp, e.data(), pool_);
        for (size_t j = 0; j < changed.size(); ++j) s.e[changed[j]] = e[j];
    }
}

void VplMethod::mark(Slot& s, uint64_t frame) {
    if (s.stale) return;
    s.stale = true;
    s.stale_since = frame;
}

void VplMethod::invalidate_all() {
    for (Slot& s : slots_) mark(s, frame_);
}

bool VplMethod::read_changes() {
    bool moved = false;
    for (const SceneChange& c : changes_since(scene_, seen_sequence_))
        if (c.kind == ChangeKind::object_transform) moved = true;
    if (!scene_.changes.empty()) seen_sequence_ = scene_.changes.back().sequence;
    return moved;
}

void VplMethod::shade(Slot& s) {
    if (s.has_next) {
        s.shown = std::move(s.next);
        s.next.clear();
        s.has_next = false;
    }
    s.stale = false;
    s.e.assign(points_.size(), glm::vec3(0.0f));
    glm::dvec3 power = cpu::total_power(s.shown);
    s.brightness = std::max({power.x, power.y, power.z});
    VplShadeStats st;
    if (!s.shown.empty())
        cpu::add_vpl_irradiance(rays_, points_, s.shown.data(), s.shown.size(),
                                scene_.settings.vpl.clamp, s.e.data(), pool_, &st);
    s.energy = st.energy;
    s.clamped = st.clamped;
}

void VplMethod::upload() {
    // Σ over slots in slot order (no running sums: no drift, the same on any thread count).
    std::fill(sum_.begin(), sum_.end(), glm::vec3(0.0f));
    for (const Slot& s : slots_)
        if (!s.e.empty())
            for (size_t i = 0; i < sum_.size(); ++i) sum_[i] += s.e[i];
    // The frame reads E/π with GL's rows bottom-first.
    std::vector<float> rgba(sum_.size() * 4, 1.0f);
    for (int y = 0; y < th_; ++y)
        for (int x = 0; x < tw_; ++x) {
            const glm::vec3 v =
                sum_[size_t(y) * size_t(tw_) + size_t(x)] * glm::one_over_pi<float>();
            float* o = &rgba[(size_t(th_ - 1 - y) * size_t(tw_) + size_t(x)) * 4];
            o[0] = v.x, o[1] = v.y, o[2] = v.z;
        }
    gpu::gl::BindTexture(GL_TEXTURE_2D, texture_.get());
    gpu::gl::TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, tw_, th_, GL_RGBA, GL_FLOAT, rgba.data());
    ++revision_;
}

void VplMethod::update(const IndirectInputs& in, PipelineStats& stats) {
    frame_ = in.frame;
    rays_.update(scene_);
    const bool moved = read_changes();
    int updated = 0;
    bool changed = false;
    if (points_.empty() || camera_version_ != scene_.camera_version) {
        // A new view makes every stored contribution useless: recompute them all now.
        (void)make_points();
        for (Slot& s : slots_) {
            shade(s);
            updated += int(s.shown.size());
        }
        changed = true;
    } else {
        if (moved) {
            // Where the mover now shows or no longer shows, the visible points are new: they get
            // the whole sum at once. It may also change what any VPL sees elsewhere (no F/P/N
            // culling yet): every slot is stale.
            const std::vector<size_t> changed_points = make_points();
            reshade_points(changed_points);
            changed = !changed_points.empty();
            invalidate_all();
        }
        std::vector<size_t> order;
        const int budget = scene_.settings.vpl.updates_per_frame;
        switch (in.mode) {
            case PipelineMode::full:
                for (size_t i = 0; i < slots_.size(); ++i) order.push_back(i);
                break;
            case PipelineMode::full_budget:
                // Round robin, knowing nothing of what changed, within the same budget.
                for (size_t n = 0, vpls = 0; n < slots_.size() && vpls < size_t(budget); ++n) {
                    const size_t i = (round_robin_ + n) % slots_.size();
                    order.push_back(i);
                    vpls += std::max(slots_[i].shown.size(), slots_[i].next.size());
                }
                if (!slots_.empty()) round_robin_ = (round_robin_ + order.size()) % slots_.size();
                break;
            case PipelineMode::selective: {
                // Barczak §4.6: priority = brightness × frames stale, K VPLs a frame.
                for (size_t i = 0; i < slots_.size(); ++i)
                    if (slots_[i].stale) order.push_back(i);
                auto priority = [&](size_t i) {
                    const Slot& s = slots_[i];
                    const double bright =
                        std::max(s.brightness, s.has_next ? [&] {
                            const glm::dvec3 p = cpu::total_power(s.next);
                            return std::max({p.x, p.y, p.z});
                        }()
                                                          : 0.0);
                    return bright * double(in.frame - std::min(in.frame, s.stale_since) + 1);
                };
                std::vector<double> pr(slots_.size(), 0.0);
                for (size_t i : order) pr[i] = priority(i);
                std::stable_sort(order.begin(), order.end(),
                                 [&](size_t a, size_t b) { return pr[a] > pr[b]; });
                size_t vpls = 0, n = 0;
                for (; n < order.size() && vpls < size_t(budget); ++n)
                    vpls += std::max<size_t>(
                        1, std::max(slots_[order[n]].shown.size(), slots_[order[n]].next.size()));
                order.resize(n);
                break;
            }
        }
        for (size_t i : order) {
            shade(slots_[i]);
            updated += int(slots_[i].shown.size());
        }
        changed = changed || !order.empty();
    }
    if (changed) upload();
    stats.vpl_updated = updated;
    stats.vpl_count = vpl_count();
    stats.vpl_stale = stale_vpls();
    stats.vpl_clamp_bias = clamp_bias();
}

void VplMethod::take_vpls(cpu::PhotonSimulation& photons, uint64_t frame) {
    if (scene_.settings.vpl.source != VplSource::photons) return;  // the thesis's set is static
    const int groups = scene_.settings.photons.groups;
    const int k = scene_.settings.vpl.photons_per_group;
    std::vector<Vpl> now;
    for (size_t l = 0; l < scene_.lights.size(); ++l)
        for (int g = 0; g < groups; ++g) {
            // A queued group still holds the hits of the old state: keep showing them until it
            // is traced again.
            if (photons.maps().group(int(l), g).queued) continue;
            now.clear();
            cpu::group_vpls(scene_, photons.maps(), int(l), g, k, now);
            Slot& s = slots_[l * size_t(groups) + size_t(g)];
            const std::vector<Vpl>& current = s.has_next ? s.next : s.shown;
            if (now == current && (s.has_next || !s.e.empty() || now.empty())) continue;
            s.next = now;
            s.has_next = true;
            mark(s, frame);
        }
}

void VplMethod::hand_over(cpu::PhotonSimulation& photons, PipelineStats& stats) {
    take_vpls(photons, frame_ + 1);
    stats.vpl_stale = stale_vpls();
}

void VplMethod::prime(cpu::PhotonSimulation& photons, uint64_t frame) {
    frame_ = frame;
    rays_.update(scene_);
    read_changes();
    take_vpls(photons, frame);
    (void)make_points();
    for (Slot& s : slots_) shade(s);
    upload();
}

gpu::IndirectTerm VplMethod::term() const {
    return gpu::IndirectTerm{texture_.get(), gpu::IndirectSpace::screen, revision_};
}

std::vector<Vpl> VplMethod::vpls() const {
    std::vector<Vpl> out;
    for (const Slot& s : slots_) out.insert(out.end(), s.shown.begin(), s.shown.end());
    return out;
}

int VplMethod::vpl_count() const {
    size_t n = 0;
    for (const Slot& s : slots_) n += s.shown.size();
    return int(n);
}

int VplMethod::stale_slots() const {
    return int(std::count_if(slots_.begin(), slots_.end(), [](const Slot& s) { return s.stale; }));
}

int VplMethod::stale_vpls() const {
    size_t n = 0;
    for (const Slot& s : slots_)
        if (s.stale) n += std::max(s.shown.size(), s.next.size());
    return int(n);
}

double VplMethod::clamp_bias() const {
    double energy = 0.0, clamped = 0.0;
    for (const Slot& s : slots_) {
        energy += s.energy;
        clamped += s.clamped;
    }
    return energy > 0.0 ? clamped / energy : 0.0;
}

}  // namespace ag
