#include "shared/pipeline/fidelity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>

#include "cpu/aim.h"
#include "cpu/cpu_gather.h"
#include "cpu/iim.h"
#include "cpu/photon_simulation.h"
#include "cpu/ray_tracer.h"
#include "cpu/reference/point_reference.h"
#include "gpu/frame_renderer.h"
#include "gpu/hemi_plane_gather.h"
#include "gpu/lightmap_texture.h"
#include "gpu/scene_meshes.h"
#include "shared/camera.h"
#include "shared/frame_terms.h"
#include "shared/gather.h"
#include "shared/lightmap_sample.h"
#include "shared/metrics.h"
#include "shared/pipeline/iim_method.h"

namespace ag {

namespace {

constexpr int kReferenceBounces = 8;  // specular bounces of the full-hemisphere reference gather

// Every texel gathered once (returned: the IIM after one gather per texel), then refined to
// settings.gather.refine_passes (left in `map`: the settled IIM).
std::vector<glm::vec3> settle_iim(cpu::Iim& map, Gatherer& gatherer, const std::vector<int>& all) {
    map.gather_records(gatherer, all, 0);
    std::vector<glm::vec3> once = map.gathered();
    for (uint64_t pass = 1; !map.complete(); ++pass) map.gather(gatherer, int(all.size()), pass);
    return once;
}

std::vector<glm::vec3> iim_of(const std::vector<GatherResult>& results) {
    std::vector<glm::vec3> out(results.size());
    for (size_t i = 0; i < results.size(); ++i) out[i] = results[i].iim;
    return out;
}

// `test` against `reference` over the texels `include` marks.
FidelityRow compare_texels(const std::string& stage, const std::string& test,
                           const std::string& reference, const std::string& region,
                           const std::vector<glm::vec3>& t, const std::vector<glm::vec3>& r,
                           const std::vector<char>& include, const std::vector<float>& area) {
    FidelityRow row{stage, test, reference, region};
    double st = 0.0, sr = 0.0, se = 0.0, peak = 0.0;
    for (size_t i = 0; i < t.size(); ++i)
        if (include[i]) peak = std::max(peak, double(luminance(r[i])));
    for (size_t i = 0; i < t.size(); ++i) {
        if (!include[i]) continue;
        const double lt = luminance(t[i]), lr = luminance(r[i]);
        st += area[i] * lt;
        sr += area[i] * lr;
        // Texels the reference holds black (under 0.1% of the brightest) have no relative error.
        if (lr > 1e-3 * peak) {
            se += (lt - lr) * (lt - lr) / (lr * lr);
            ++row.count;
        }
    }
    row.mean_ratio = sr > 0.0 ? st / sr : 0.0;
    row.rms = row.count > 0 ? std::sqrt(se / row.count) : 0.0;
    return row;
}

FidelityRow compare_pixels(const std::string& stage, const std::string& test,
                           const std::string& reference, const std::string& region, const Image& t,
                           const Image& r, const Image& mask) {
    FidelityRow row{stage, test, reference, region};
    double st = 0.0, sr = 0.0, se = 0.0;
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x) {
            if (mask.at(x, y)[0] == 0.0f) continue;
            const double lt = luminance(t.rgb(x, y)), lr = luminance(r.rgb(x, y));
            row.test_mean += glm::dvec3(t.rgb(x, y));
            row.reference_mean += glm::dvec3(r.rgb(x, y));
            st += lt;
            sr += lr;
            if (lr > 0.0) se += (lt - lr) * (lt - lr) / (lr * lr);
            ++row.count;
        }
    if (row.count == 0) return row;
    row.test_mean /= double(row.count);
    row.reference_mean /= double(row.count);
    row.mean_ratio = sr > 0.0 ? st / sr : 0.0;
    row.rms = std::sqrt(se / row.count);
    row.rel_mse = compare_images(t, r, &mask).rel_mse;
    return row;
}

}  // namespace

FidelityReport measure_fidelity(Scene& scene, const FidelityOptions& options, ThreadPool& pool) {
    FidelityReport report;
    const LightmapAtlas& atlas = scene.atlas;
    const size_t records = atlas.texels.size();
    const Settings saved = scene.settings;

    cpu::PhotonSimulation photons(scene, pool);
    photons.trace_all();
    cpu::Aim aim(scene, pool);
    aim.rebuild_all(photons.maps());
    const std::vector<glm::vec3>& aim_radiance = aim.radiance();
    const cpu::RayTracer rays(scene);

    std::vector<int> all(records);
    std::vector<cpu::SurfacePoint> points(records);
    std::vector<float> area(records);
    std::vector<glm::vec3> albedo(records), aim_texel(records);
    std::vector<std::string> object_of(records);
    for (size_t r = 0; r < records; ++r) {
        all[r] = int(r);
        const TexelRecord& t = atlas.texels[r];
        const Object& o = scene.objects[size_t(t.object)];
        points[r] = {o.transform.apply_point(t.position),
                     glm::normalize(o.transform.apply_vector(t.normal))};
        area[r] = t.area;
        albedo[r] = o.material.albedo;
        object_of[r] = o.name;
        aim_texel[r] = aim_radiance[size_t(t.y) * size_t(atlas.width) + size_t(t.x)];
    }
    auto& values = report.texel_values;
    values["aim"] = aim_texel;

    // Exact: path-traced irradiance at the texel centres.
    const std::vector<cpu::PointIrradiance> exact =
        cpu::path_traced_irradiance(scene, rays, points, options.pt_paths, 256, saved.seed, pool);
    std::vector<glm::vec3> pt_radiance(records), pt_indirect(records);
    for (size_t r = 0; r < records; ++r) {
        pt_radiance[r] =
            albedo[r] / std::numbers::pi_v<float> * (exact[r].direct + exact[r].indirect);
        pt_indirect[r] = exact[r].indirect / std::numbers::pi_v<float>;
    }
    values["pt_radiance"] = pt_radiance;
    values["pt_indirect"] = pt_indirect;

    // Gathers of the same AIMs under varied settings (the scene's settings restored after each).
    auto cpu_gather = [&](int rays_per_texel, GatherHemisphere hemisphere,
                          BorderCorrection correction, int bounces) {
        scene.settings.gather.cpu_rays = rays_per_texel;
        scene.settings.gather.hemisphere = hemisphere;
        scene.settings.gather.border_correction = correction;
        scene.settings.gather.specular_bounces = bounces;
        cpu::CpuGather gather(scene, rays, pool);
        std::vector<GatherResult> out = gather.gather(all, aim_radiance);
        scene.settings = saved;
        return out;
    };
    const int n_ref = options.reference_rays;
    const std::vector<GatherResult> full =
        cpu_gather(n_ref, GatherHemisphere::full, BorderCorrection::none, kReferenceBounces);
    values["full"] = iim_of(full);
    values["full_black"] =
        iim_of(cpu_gather(n_ref, GatherHemisphere::full, BorderCorrection::none, 0));
    report.texel_valid.resize(records);
    for (size_t r = 0; r < records; ++r)
        report.texel_valid[r] = full[r].back_fraction <= kBackFaceInvalidFraction;

    struct Variant {
        std::string name;
        BorderCorrection correction;
    };
    const std::vector<Variant> corrections = {{"none", BorderCorrection::none},
                                              {"renormalize", BorderCorrection::renormalize},
                                              {"stretch", BorderCorrection::stretch},
                                              {"stretch_radial", BorderCorrection::stretch_radial},
                                              {"band", BorderCorrection::band}};
    const std::vector<Variant> variants =
        options.gather_variants ? corrections : std::vector<Variant>{};
    for (const Variant& v : variants)
        values["cpu_plane_" + v.name] =
            iim_of(cpu_gather(n_ref, GatherHemisphere::plane, v.correction, 0));
    if (options.gather_variants)
        values["cpu_full_" + std::to_string(saved.gather.cpu_rays)] =
            iim_of(cpu_gather(saved.gather.cpu_rays, GatherHemisphere::full, BorderCorrection::none,
                              saved.gather.specular_bounces));

    std::unique_ptr<gpu::SceneMeshes> meshes;
    std::unique_ptr<gpu::LightmapTexture> aim_texture;
    if (options.gl) {
        meshes = std::make_unique<gpu::SceneMeshes>(scene);
        aim_texture = std::make_unique<gpu::LightmapTexture>(atlas);
        aim_texture->update_all(aim_radiance);
        for (const Variant& v : variants) {
            scene.settings.gather.border_correction = v.correction;
            scene.settings.gather.specular_bounces = 0;
            gpu::HemiPlaneGather gather(scene, *meshes, 256, aim_texture.get());
            values["gl_plane_" + v.name] = iim_of(gather.gather(all));
            scene.settings = saved;
        }
    }

    // What the pipeline gathers with these settings (the CPU rays, or the GL hemi-plane with
    // texels that see mirrors or glass handed to the rays), through cpu::Iim as the pipeline
    // does: invalid texels gathered at their footprint or repaired from neighbours.
    std::vector<glm::vec3> iim, once;
    {
        cpu::CpuGather rays_gather(scene, rays, pool, &aim_radiance);
        cpu::Iim map(scene);
        // `automatic` as the pipeline resolves it (the CPU rays on a software rasteriser).
        const GatherBackend backend = saved.gather.backend == GatherBackend::automatic && options.gl
                                          ? automatic_gather_backend()
                                          : saved.gather.backend;
        if (options.gl && backend != GatherBackend::cpu) {
            gpu::HemiPlaneGather plane(scene, *meshes, 256, aim_texture.get());
            SpecularRoutedGather routed(plane, rays_gather);
            if (saved.gather.specular_bounces > 0) {
                once = settle_iim(map, routed, all);
                report.routed = routed.total_routed();
            } else {
                once = settle_iim(map, plane, all);
            }
        } else {
            once = settle_iim(map, rays_gather, all);
        }
        iim = map.gathered();
    }
    // "pipeline": one gather per texel (what stage b holds to the full gather); "refined": the
    // settled IIM, each texel the mean of settings.gather.refine_passes gathers over its
    // footprint, which the frame shows.
    auto per_record = [&](const std::vector<glm::vec3>& atlas_values) {
        std::vector<glm::vec3> out(records);
        for (size_t r = 0; r < records; ++r)
            out[r] = atlas_values[size_t(atlas.texels[r].y) * size_t(atlas.width) +
                                  size_t(atlas.texels[r].x)];
        return out;
    };
    values["pipeline"] = per_record(once);
    values["refined"] = per_record(iim);

    // Rows per stage, for the whole scene and per object.
    std::vector<std::string> regions = {"all"};
    for (const Object& o : scene.objects)
        if (std::find(object_of.begin(), object_of.end(), o.name) != object_of.end())
            regions.push_back(o.name);
    auto add_texel_rows = [&](const std::string& stage, const std::string& test,
                              const std::string& reference) {
        if (!values.count(test) || !values.count(reference)) return;
        for (const std::string& region : regions) {
            std::vector<char> include(records);
            for (size_t r = 0; r < records; ++r)
                include[r] = report.texel_valid[r] && (region == "all" || object_of[r] == region) &&
                             luminance(albedo[r]) > 0.0f;
            report.rows.push_back(compare_texels(stage, test, reference, region, values[test],
                                                 values[reference], include, area));
        }
    };
    add_texel_rows("a", "aim", "pt_radiance");
    for (const Variant& v : corrections) add_texel_rows("b", "gl_plane_" + v.name, "full_black");
    for (const Variant& v : corrections) add_texel_rows("b", "cpu_plane_" + v.name, "full_black");
    add_texel_rows("b", "cpu_full_" + std::to_string(saved.gather.cpu_rays), "full");
    add_texel_rows("b", "full_black", "full");
    add_texel_rows("b", "pipeline", "full");
    add_texel_rows("b", "refined", "full");
    add_texel_rows("c", "full", "pt_indirect");
    add_texel_rows("c", "pipeline", "pt_indirect");
    add_texel_rows("c", "refined", "pt_indirect");

    if (!options.gl) return report;

    // (d) The IIM as the camera sees it: the pipeline's IIM above uploaded (dilated) and read by
    // the frame, against gathering at every pixel.
    gpu::LightmapTexture iim_texture(atlas);
    iim_texture.update_all(iim);
    const int w = options.width, h = options.height;
    const Camera camera = scene.camera;
    scene.camera.width = w;
    scene.camera.height = h;
    gpu::FrameRenderer renderer(scene, *meshes, w, h);
    renderer.render(iim_texture.id(), 0);
    report.frame_indirect = renderer.read_back().aov[size_t(FrameTerm::indirect)];

    // Pixels that see a diffuse front face, and the regions each belongs to: its object, the
    // object's part in the shadow of another object (a shadow ray to some light blocked by it),
    // and its part within one texel of another object's bounds (contacts, beside thin walls).
    std::vector<GatherPoint> pixel_points;
    std::vector<std::pair<int, int>> pixel_of;
    std::vector<glm::vec3> pixel_albedo;
    std::map<std::string, Image> region_masks;
    std::vector<std::string> region_order = {"all"};
    std::vector<Bounds> bounds(scene.objects.size());
    for (size_t o = 0; o < scene.objects.size(); ++o)
        for (const glm::vec3& v : scene.objects[o].mesh.positions)
            bounds[o].add(scene.objects[o].transform.apply_point(v));
    auto mark = [&](const std::string& name, int x, int y) {
        auto [it, inserted] = region_masks.try_emplace(name, w, h);
        if (inserted) region_order.push_back(name);
        it->second.set_rgb(x, y, glm::vec3(1.0f));
    };
    region_masks.emplace("all", Image(w, h));
    // Object per pixel centre first: regions other than "all" leave out pixels on an object's
    // outline, where a box-filtered reference mixes two surfaces into one pixel.
    std::vector<int> object_at(size_t(w) * size_t(h), -1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec3 d =
                camera_ray_direction(scene.camera, float(x) + 0.5f, float(y) + 0.5f);
            const cpu::RayHit hit = rays.intersect({scene.camera.eye, d, 0.0f, 1e30f});
            object_at[size_t(y) * size_t(w) + size_t(x)] = hit.hit ? hit.object : -1;
        }
    auto outline = [&](int x, int y) {
        const int self = object_at[size_t(y) * size_t(w) + size_t(x)];
        for (const auto& [dx, dy] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
            const int nx = std::clamp(x + dx, 0, w - 1), ny = std::clamp(y + dy, 0, h - 1);
            if (object_at[size_t(ny) * size_t(w) + size_t(nx)] != self) return true;
        }
        return false;
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec3 d =
                camera_ray_direction(scene.camera, float(x) + 0.5f, float(y) + 0.5f);
            const cpu::RayHit hit = rays.intersect({scene.camera.eye, d, 0.0f, 1e30f});
            if (!hit.hit) continue;
            const Material& m = scene.objects[size_t(hit.object)].material;
            if (m.type != MaterialType::diffuse || glm::dot(d, hit.normal) >= 0.0f) continue;
            pixel_points.push_back({hit.position, hit.normal, uint32_t(y * w + x)});
            pixel_of.emplace_back(x, y);
            pixel_albedo.push_back(m.albedo);
            const std::string& name = scene.objects[size_t(hit.object)].name;
            mark("all", x, y);
            if (outline(x, y)) continue;
            mark(name, x, y);
            const glm::vec3 origin = hit.position + rays.epsilon() * hit.normal;
            std::vector<char> shadowed_by(scene.objects.size(), 0);
            for (const Light& light : scene.lights) {
                if (!light.enabled) continue;
                const glm::vec3 to = light.center() - origin;
                if (glm::dot(to, hit.normal) <= 0.0f) continue;
                const cpu::RayHit blocker = rays.intersect({origin, to, 0.0f, 0.999f});
                if (blocker.hit && blocker.object != hit.object)
                    shadowed_by[size_t(blocker.object)] = 1;
            }
            for (size_t o = 0; o < scene.objects.size(); ++o) {
                if (int(o) == hit.object) continue;
                if (shadowed_by[o]) mark(name + "/shadow:" + scene.objects[o].name, x, y);
                const glm::vec3 nearest = glm::clamp(hit.position, bounds[o].min, bounds[o].max);
                if (glm::length(nearest - hit.position) < atlas.texel_size)
                    mark(name + "/near:" + scene.objects[o].name, x, y);
            }
        }
    scene.camera = camera;
    scene.settings.gather.cpu_rays = options.pixel_rays;
    scene.settings.gather.hemisphere = GatherHemisphere::full;
    scene.settings.gather.specular_bounces = kReferenceBounces;
    cpu::CpuGather pixel_gather(scene, rays, pool);
    const std::vector<GatherResult> per_pixel =
        pixel_gather.gather_points(pixel_points, aim_radiance);
    scene.settings = saved;
    report.pixel_indirect = Image(w, h);
    report.mask = Image(w, h);
    for (size_t i = 0; i < per_pixel.size(); ++i) {
        const auto [x, y] = pixel_of[i];
        report.pixel_indirect.set_rgb(x, y, pixel_albedo[i] * per_pixel[i].iim);
        report.mask.set_rgb(x, y, glm::vec3(1.0f));
    }
    const bool with_pt =
        options.reference_indirect.width == w && options.reference_indirect.height == h;
    if (options.pt_pixels > 0) {
        std::vector<cpu::SurfacePoint> centres;
        centres.reserve(pixel_points.size());
        for (const GatherPoint& g : pixel_points) centres.push_back({g.position, g.normal});
        const std::vector<cpu::PointIrradiance> at_pixels = cpu::path_traced_irradiance(
            scene, rays, centres, options.pt_pixels, 1, saved.seed, pool);
        report.pt_pixels = Image(w, h);
        for (size_t i = 0; i < at_pixels.size(); ++i) {
            const auto [x, y] = pixel_of[i];
            report.pt_pixels.set_rgb(
                x, y, pixel_albedo[i] * at_pixels[i].indirect / std::numbers::pi_v<float>);
        }
    }
    // Shadows split at their mean column: the two halves' tints say whether the light seen
    // through a glass ball lands on the right side (the Cornell floor under the sphere).
    for (size_t i = 0, n = region_order.size(); i < n; ++i) {
        const std::string name = region_order[i];
        if (name.find("/shadow:") == std::string::npos) continue;
        const Image& mask = region_masks.at(name);
        double sum_x = 0.0;
        int count = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                if (mask.at(x, y)[0] != 0.0f) sum_x += x, ++count;
        if (count == 0) continue;
        const double mid = sum_x / count;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                if (region_masks.at(name).at(x, y)[0] != 0.0f)
                    mark(name + (double(x) < mid ? "/image_left" : "/image_right"), x, y);
    }
    for (const std::string& region : region_order) {
        const Image& mask = region_masks.at(region);
        int included = 0;
        for (size_t i = 0; i < mask.pixels.size(); i += 3) included += mask.pixels[i] != 0.0f;
        if (included < 16) continue;  // too few pixels to say anything
        report.rows.push_back(compare_pixels("d", "frame", "pixel_gather", region,
                                             report.frame_indirect, report.pixel_indirect, mask));
        if (with_pt) {
            report.rows.push_back(compare_pixels("e", "pixel_gather", "pt_image", region,
                                                 report.pixel_indirect, options.reference_indirect,
                                                 mask));
            report.rows.push_back(compare_pixels("e", "frame", "pt_image", region,
                                                 report.frame_indirect, options.reference_indirect,
                                                 mask));
            if (options.pt_pixels > 0)
                report.rows.push_back(compare_pixels("e", "pt_pixels", "pt_image", region,
                                                     report.pt_pixels, options.reference_indirect,
                                                     mask));
        }
        if (options.pt_pixels > 0)
            report.rows.push_back(compare_pixels("e", "pixel_gather", "pt_pixels", region,
                                                 report.pixel_indirect, report.pt_pixels, mask));
    }
    return report;
}

std::string fidelity_table(const FidelityReport& report) {
    std::ostringstream out;
    char line[256];
    std::snprintf(line, sizeof line, "%-5s %-22s %-14s %-12s %6s %8s %8s %8s\n", "stage", "test",
                  "reference", "region", "count", "ratio", "rms%", "relMSE");
    out << line;
    for (const FidelityRow& r : report.rows) {
        std::snprintf(line, sizeof line, "%-5s %-22s %-14s %-12s %6d %8.4f %8.2f %8.4f\n",
                      r.stage.c_str(), r.test.c_str(), r.reference.c_str(), r.region.c_str(),
                      r.count, r.mean_ratio, 100.0 * r.rms, r.rel_mse);
        out << line;
    }
    return out.str();
}

std::string fidelity_csv(const Scene& scene, const FidelityReport& report) {
    std::ostringstream out;
    out << "stage,test,reference,region,count,mean_ratio,rms_relative,rel_mse,test_r,test_g,"
           "test_b,reference_r,reference_g,reference_b\n";
    for (const FidelityRow& r : report.rows)
        out << r.stage << ',' << r.test << ',' << r.reference << ',' << r.region << ',' << r.count
            << ',' << r.mean_ratio << ',' << r.rms << ',' << r.rel_mse << ',' << r.test_mean.r
            << ',' << r.test_mean.g << ',' << r.test_mean.b << ',' << r.reference_mean.r << ','
            << r.reference_mean.g << ',' << r.reference_mean.b << '\n';
    out << "\nrecord,object,x,y,z,nx,ny,nz,valid,area";
    for (const auto& [name, v] : report.texel_values)
        out << ',' << name << "_r," << name << "_g," << name << "_b";
    out << '\n';
    for (size_t r = 0; r < scene.atlas.texels.size(); ++r) {
        const TexelRecord& t = scene.atlas.texels[r];
        const Object& o = scene.objects[size_t(t.object)];
        const glm::vec3 p = o.transform.apply_point(t.position);
        const glm::vec3 n = glm::normalize(o.transform.apply_vector(t.normal));
        out << r << ',' << o.name << ',' << p.x << ',' << p.y << ',' << p.z << ',' << n.x << ','
            << n.y << ',' << n.z << ',' << int(report.texel_valid[r]) << ',' << t.area;
        for (const auto& [name, v] : report.texel_values)
            out << ',' << v[r].r << ',' << v[r].g << ',' << v[r].b;
        out << '\n';
    }
    return out.str();
}

}  // namespace ag
