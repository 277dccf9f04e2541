#include "shared/pipeline/vpl_method.h"

#include <algorithm>
#include <glm/gtc/constants.hpp>
#include <numeric>

#include "gpu/gl.h"
#include "shared/scene_edit.h"

namespace ag {

namespace {
// Random-walk VPLs are grouped this many paths to a slot (a slot is the unit of update).
constexpr int kWalkPathsPerSlot = 25;
}  // namespace

VplMethod::VplMethod(const Scene& scene, const gpu::SceneMeshes& meshes, int width, int height)
    : scene_(scene),
      backend_(scene.settings.vpl.backend),
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
    if (backend_ == VplBackend::gl) {
        Bounds b;
        for (const Object& o : scene.objects)
            for (const glm::vec3& p : o.mesh.positions) b.add(o.transform.apply_point(p));
        const float near = 1e-4f * std::max(1e-3f, glm::length(b.extent()));
        maps_ = std::make_unique<gpu::VplShadowMaps>(scene, meshes, scene.settings.vpl.map_size,
                                                     scene.settings.vpl.map, near);
        gather_ = std::make_unique<gpu::VplGather>(tw_, th_);
    }
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
    if (maps_) {
        // Before any frame: the most maps layout() can ask for (each slot's room, half as many
        // again as its VPLs: a photon group yields at most photons_per_group) must fit the GL's
        // array layers as an atlas, or the scene fails here, naming the setting to lower.
        size_t most = 0;
        for (const Slot& s : slots_) {
            const size_t k =
                vs.source == VplSource::photons ? size_t(vs.photons_per_group) : s.next.size();
            most += (k * 3 + 1) / 2;
        }
        (void)gpu::vpl_map_layout(int(std::min<size_t>(most, size_t(1) << 30)), vs.map_size,
                                  maps_->limits());
    }
}

std::vector<size_t> VplMethod::make_points() {
    camera_version_ = scene_.camera_version;
    const std::vector<cpu::SurfacePoint> before = std::move(points_);
    points_ = cpu::camera_points(scene_, rays_, tw_, th_, pool_, &hits_);
    std::vector<size_t> changed;
    for (size_t i = 0; i < points_.size(); ++i)
        if (before.size() != points_.size() || before[i].position != points_[i].position ||
            before[i].normal != points_[i].normal)
            changed.push_back(i);
    return changed;
}

void VplMethod::reshade_points(const std::vector<size_t>& changed) {
    if (changed.empty() || backend_ != VplBackend::cpu) return;
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

void VplMethod::refresh(Slot& s) {
    if (s.has_next) {
        s.shown = std::move(s.next);
        s.next.clear();
        s.has_next = false;
    }
    s.stale = false;
    s.shown_once = true;
    const glm::dvec3 power = cpu::total_power(s.shown);
    s.brightness = std::max({power.x, power.y, power.z});
    if (backend_ == VplBackend::cpu) {
        shade(s);
        return;
    }
    if (int(s.shown.size()) > s.layers) return;  // layout() makes room, then renders all
    for (int i = 0; i < s.layers; ++i)
        records_[size_t(s.layer + i)] = i < int(s.shown.size()) ? s.shown[size_t(i)] : Vpl{};
    records_dirty_ = true;
}

bool VplMethod::layout() {
    bool fits = !records_.empty();
    for (const Slot& s : slots_) fits = fits && int(s.shown.size()) <= s.layers;
    if (fits) return false;
    // Room for half as many again as each slot holds now (photon groups vary a little).
    int layer = 0;
    for (Slot& s : slots_) {
        s.layer = layer;
        s.layers = (int(s.shown.size()) * 3 + 1) / 2;
        layer += s.layers;
    }
    records_.assign(size_t(std::max(1, layer)), Vpl{});
    for (const Slot& s : slots_)
        for (size_t i = 0; i < s.shown.size(); ++i) records_[size_t(s.layer) + i] = s.shown[i];
    records_dirty_ = true;
    return true;
}

void VplMethod::render_maps(const Slot& s) {
    if (s.layers > 0) maps_->render(s.layer, s.layers);
}

void VplMethod::upload_points() {
    // The gather reads the points per pixel with GL's rows bottom-first.
    std::vector<glm::vec3> positions(points_.size()), normals(points_.size());
    for (int y = 0; y < th_; ++y)
        for (int x = 0; x < tw_; ++x) {
            const cpu::SurfacePoint& p = points_[size_t(y) * size_t(tw_) + size_t(x)];
            const size_t i = size_t(th_ - 1 - y) * size_t(tw_) + size_t(x);
            positions[i] = p.position;
            normals[i] = p.normal;
        }
    gather_->set_points(positions, normals);
    tiles_dirty_ = true;
}

void VplMethod::build_tiles() {
    const VplSettings& vs = scene_.settings.vpl;
    if (!vs.labels) {
        gather_->set_tiles(records_, vs.interleave);
        tiles_dirty_ = false;
        return;
    }
    // The thesis's VPLs are static, so its database is built once and updated by Table 4-1;
    // ours change with their photon groups, so it is rebuilt for the records now.
    database_ = std::make_unique<cpu::VisibilityDatabase>(scene_, records_, 2);
    std::vector<glm::vec3> positions(points_.size()), normals(points_.size());
    std::vector<int> patches(points_.size(), 0);
    for (int y = 0; y < th_; ++y)
        for (int x = 0; x < tw_; ++x) {
            const size_t from = size_t(y) * size_t(tw_) + size_t(x);
            const size_t i = size_t(th_ - 1 - y) * size_t(tw_) + size_t(x);
            positions[i] = points_[from].position;
            normals[i] = points_[from].normal;
            const cpu::RayHit& h = hits_[from];
            // A point on a surface with no patches (mirror, glass) takes every lookup.
            const int leaf = h.hit ? database_->leaf_at(h.object, h.triangle, h.barycentric) : -1;
            patches[i] = leaf < 0 ? int(database_->nodes().size()) : leaf;
        }
    const size_t count = records_.size();
    std::vector<uint32_t> labels((database_->nodes().size() + 1) * count, 1u);
    for (size_t node = 0; node < database_->nodes().size(); ++node)
        for (size_t l = 0; l < count; ++l)
            labels[node * count + l] = uint32_t(database_->state(int(node), int(l)));
    gather_->set_points(positions, normals, patches);
    gather_->set_tiles(records_, vs.interleave, &labels);
    tiles_dirty_ = false;
}

void VplMethod::shade(Slot& s) {
    s.e.assign(points_.size(), glm::vec3(0.0f));
    cpu::VplShadeStats st;
    if (!s.shown.empty())
        cpu::add_vpl_irradiance(rays_, points_, s.shown.data(), s.shown.size(),
                                scene_.settings.vpl.clamp, s.e.data(), pool_, &st);
    s.energy = st.energy;
    s.clamped = st.clamped;
}

void VplMethod::upload() {
    ++revision_;
    if (backend_ == VplBackend::gl) {
        if (scene_.settings.vpl.tiles && tiles_dirty_) build_tiles();
        gather_->shade(*maps_, scene_.settings.vpl.clamp, glm::one_over_pi<float>());
        return;
    }
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
        if (backend_ == VplBackend::gl) {
            upload_points();
        } else {
            for (Slot& s : slots_) {
                if (s.shown_once) shade(s);
                updated += int(s.shown.size());
            }
        }
        changed = true;
    } else {
        if (moved) {
            // Where the mover now shows or no longer shows, the visible points are new: they get
            // the whole sum at once. It may also change what any VPL sees elsewhere (no F/P/N
            // culling yet): every slot is stale.
            const std::vector<size_t> changed_points = make_points();
            reshade_points(changed_points);
            if (backend_ == VplBackend::gl && !changed_points.empty()) upload_points();
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
        refresh(order);
        for (size_t i : order) updated += int(slots_[i].shown.size());
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
            if (now == current && (s.has_next || s.shown_once || now.empty())) continue;
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
    if (backend_ == VplBackend::gl) upload_points();
    std::vector<size_t> all(slots_.size());
    std::iota(all.begin(), all.end(), size_t(0));
    refresh(all);
    upload();
}

void VplMethod::refresh(const std::vector<size_t>& slots) {
    for (size_t i : slots) refresh(slots_[i]);
    if (backend_ != VplBackend::gl) return;
    if (layout()) {
        maps_->set_vpls(records_);
        maps_->render_all();
        tiles_dirty_ = true;
    } else {
        if (records_dirty_) maps_->set_vpls(records_);
        tiles_dirty_ = tiles_dirty_ || records_dirty_;
        for (size_t i : slots) render_maps(slots_[i]);
    }
    records_dirty_ = false;
}

gpu::IndirectTerm VplMethod::term() const {
    const GLuint t = backend_ == VplBackend::gl ? gather_->texture() : texture_.get();
    return gpu::IndirectTerm{t, gpu::IndirectSpace::screen, revision_};
}

std::vector<glm::vec3> VplMethod::irradiance() const {
    if (backend_ == VplBackend::cpu) return sum_;
    const std::vector<glm::vec3> e = gather_->read_back();  // E/π, rows bottom-first
    std::vector<glm::vec3> out(e.size());
    for (int y = 0; y < th_; ++y)
        for (int x = 0; x < tw_; ++x)
            out[size_t(y) * size_t(tw_) + size_t(x)] =
                e[size_t(th_ - 1 - y) * size_t(tw_) + size_t(x)] * glm::pi<float>();
    return out;
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
