// The Python module `afterglow._afterglow` (pybind11; docs/python.md): scenes and their edits (the
// scene_edit.h API the Lua scripts use), the progressive pipeline, references, metrics and the
// convergence study of `afterglow converge`, over libafterglow.so. Frames, references and studies
// run with the GIL released. User errors raise afterglow.InputError (a ValueError) with the
// message the command line prints.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cpu/reference/reference.h"
#include "gpu/gl_context.h"
#include "shared/frame_terms.h"
#include "shared/image.h"
#include "shared/input_error.h"
#include "shared/metrics.h"
#include "shared/parallel.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/pipeline/pipeline.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/script.h"
#include "shared/settings_json.h"
#include "tools/afterglow/convergence.h"

namespace py = pybind11;

namespace ag::python {
namespace {

using Vec3 = std::array<float, 3>;

glm::vec3 to_glm(const Vec3& v) { return {v[0], v[1], v[2]}; }
Vec3 to_tuple(const glm::vec3& v) { return {v.x, v.y, v.z}; }

// A scene shared by Python objects (the Scene, its object and light handles, pipelines). `busy`
// is set while a pipeline runs frames on it with the GIL released: edits are refused then.
struct SceneHolder {
    Scene scene;
    std::atomic<int> busy{0};

    Scene& for_edit() {
        if (busy.load() != 0)
            throw std::runtime_error(
                "the scene is being rendered (Pipeline.run in another thread); edit it between "
                "runs");
        return scene;
    }
};
using SceneRef = std::shared_ptr<SceneHolder>;

struct BusyGuard {
    explicit BusyGuard(SceneHolder& h) : holder(h) { ++holder.busy; }
    ~BusyGuard() { --holder.busy; }
    BusyGuard(const BusyGuard&) = delete;
    BusyGuard& operator=(const BusyGuard&) = delete;
    SceneHolder& holder;
};

// "no object named 'x' (the scene has: a, b, c)", as the Lua API says it.
template <class Items>
[[noreturn]] void no_such(const char* kind, const std::string& name, const Items& items) {
    std::string names;
    for (size_t i = 0; i < items.size(); ++i) names += (i > 0 ? ", " : "") + items[i].name;
    throw InputError(std::string("no ") + kind + " named '" + name + "' (the scene has: " + names +
                     ")");
}

// ---- images <-> numpy ------------------------------------------------------------------------

py::array_t<float> to_numpy(const Image& image) {
    py::array_t<float> a({py::ssize_t(image.height), py::ssize_t(image.width), py::ssize_t(3)});
    float* out = a.mutable_data();
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const glm::vec3 c = pixel_rgb(image, x, y);
            float* p = out + (size_t(y) * size_t(image.width) + size_t(x)) * 3;
            p[0] = c.r, p[1] = c.g, p[2] = c.b;
        }
    return a;
}

// (H, W, 3) or (H, W) (grey) float array → Image; `what` names the argument in errors.
Image to_image(const py::handle& object, const char* what) {
    const auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(object);
    if (!a) throw py::type_error(std::string(what) + ": expected a float array of shape (H, W, 3)");
    if (!(a.ndim() == 3 && a.shape(2) == 3) && a.ndim() != 2)
        throw py::value_error(
            std::string(what) + ": expected an array of shape (H, W, 3) or (H, W), got " +
            std::to_string(a.ndim()) + " dimensions" +
            (a.ndim() == 3 ? " with " + std::to_string(a.shape(2)) + " channels" : std::string()));
    Image image(int(a.shape(1)), int(a.shape(0)), a.ndim() == 3 ? 3 : 1);
    std::copy(a.data(), a.data() + a.size(), image.pixels.begin());
    return image;
}

// ---- dict <-> JSON text, through Python's json module -----------------------------------------

std::string json_dumps(const py::handle& object) {
    return py::module_::import("json").attr("dumps")(object).cast<std::string>();
}

// ---- object and light handles -------------------------------------------------------------------

struct ObjectHandle {
    SceneRef holder;
    int index = 0;
    const Object& get() const { return holder->scene.objects[size_t(index)]; }
};

struct LightHandle {
    SceneRef holder;
    int index = 0;
    const Light& get() const { return holder->scene.lights[size_t(index)]; }
};

py::dict camera_dict(const Camera& c) {
    py::dict d;
    d["eye"] = to_tuple(c.eye);
    d["target"] = to_tuple(c.target);
    d["up"] = to_tuple(c.up);
    d["fov_y"] = c.fov_y;
    d["resolution"] = std::array<int, 2>{c.width, c.height};
    return d;
}

// ---- the pipeline -------------------------------------------------------------------------------

gpu::GlBackend parse_backend(const std::string& name) {
    if (name == "window") throw py::value_error("gl: the window backend is for the viewer only");
    return gpu::parse_gl_backend(name);
}

py::dict stats_dict(const PipelineStats& s) {
    py::dict d;
    d["frame"] = s.frame;
    d["frame_ms"] = s.frame_ms;
    d["photon_ms"] = s.photon_ms;
    d["aim_ms"] = s.aim_ms;
    d["caustic_ms"] = s.caustic_ms;
    d["gather_ms"] = s.gather_ms;
    d["texel_gather_ms"] = s.texel_gather_ms;
    d["gather_rays"] = s.gather_rays;
    d["gather_rays_reused"] = s.gather_rays_reused;
    d["hand_overs"] = s.hand_overs;
    d["workers_behind"] = s.workers_behind;
    d["draw_ms"] = s.draw_ms;
    d["wait_ms"] = s.wait_ms;
    d["early_hand_over"] = s.early_hand_over;
    d["caustics_drawn"] = s.caustics_drawn;
    d["caustics_draw_ms"] = s.caustics_draw_ms;
    d["cube_faces_relit"] = s.cube_faces_relit;
    d["cube_faces_ms"] = s.cube_faces_ms;
    d["drawn"] = s.drawn;
    d["photons_verified"] = s.photons.photons_verified;
    d["groups_invalidated"] = s.photons.groups_invalidated;
    d["groups_invalidated_by_query"] = s.photons.groups_invalidated_by_query;
    d["photons_retraced"] = s.photons.photons_retraced;
    d["groups_retraced"] = s.photons.groups_retraced;
    d["groups_queued"] = s.photons.groups_queued;
    d["aim_texels_rebuilt"] = s.photons.aim_texels_rebuilt;
    d["aim_surfaces_rebuilt"] = s.photons.aim_surfaces_rebuilt;
    d["iim_texels_gathered"] = s.iim_texels_gathered;
    d["iim_texels_pending"] = s.iim_texels_pending;
    d["iim_texels_invalid"] = s.iim_texels_invalid;
    d["caustic_photons_traced"] = s.caustics.traced;
    d["caustic_photons_hit_specular"] = s.caustics.hit_specular;
    d["caustic_photons_stored"] = s.caustics.stored;
    d["caustic_tiles_filtered"] = s.caustic_tiles_filtered;
    d["budget_iim_texels"] = s.budget_iim_texels;
    d["budget_photons"] = s.budget_photons;
    return d;
}

PipelineMode parse_mode(const std::string& name) {
    for (size_t i = 0; i < kPipelineModeNames.size(); ++i)
        if (name == kPipelineModeNames[i]) return PipelineMode(i);
    throw py::value_error("mode: unknown pipeline mode '" + name +
                          "' (expected selective, full or full-budget)");
}

std::optional<FrameTerm> parse_component(const std::string& name) {
    if (name == "full") return std::nullopt;
    if (auto t = parse_frame_term(name)) return t;
    throw py::value_error("unknown component '" + name +
                          "' (expected full, direct, indirect, caustics, specular or volume)");
}

void apply_settings(Scene& scene, const py::object& settings) {
    if (settings.is_none()) return;
    if (!py::isinstance<py::dict>(settings))
        throw py::type_error("settings: expected a dict shaped like a scene file's \"settings\"");
    apply_settings_json(scene, json_dumps(settings), "settings");
}

class PyPipeline {
public:
    PyPipeline(SceneRef holder, const py::object& settings, std::optional<std::array<int, 2>> size,
               std::optional<int> threads, const std::string& mode, const std::string& gl,
               std::optional<std::string> script)
        : holder_(std::move(holder)) {
        Scene& scene = holder_->for_edit();
        // A pipeline that refuses its settings must leave the scene as it was: the settings go
        // back (through apply_settings_json, so a changed lightmap is rebuilt back too).
        const std::string settings_before = settings_to_json_value(scene.settings).dump();
        apply_settings(scene, settings);
        try {
            build(scene, size, threads, mode, gl, script);
        } catch (...) {
            loop_.reset();
            if (context_) context_->make_current();
            pipeline_.reset();
            context_.reset();
            apply_settings_json(scene, settings_before, "settings");
            throw;
        }
    }

    ~PyPipeline() {
        if (!context_) return;
        context_->make_current();
        loop_.reset();
        pipeline_.reset();
    }

private:
    void build(Scene& scene, std::optional<std::array<int, 2>> size, std::optional<int> threads,
               const std::string& mode, const std::string& gl, std::optional<std::string> script) {
        int width = scene.camera.width, height = scene.camera.height;
        if (size) {
            width = (*size)[0], height = (*size)[1];
            if (width < 1 || height < 1 || width > 16384 || height > 16384)
                throw py::value_error("size: expected (width, height) within 1..16384, got (" +
                                      std::to_string(width) + ", " + std::to_string(height) + ")");
        }
        const PipelineMode pipeline_mode = parse_mode(mode);
        const std::string script_path = script ? *script : scene.script;
        if (!script_path.empty()) script_.emplace(script_path);
        context_ = gpu::make_gl_context(parse_backend(gl));
        pipeline_ = std::make_unique<Pipeline>(
            scene, PipelineOptions{width, height, threads.value_or(scene.settings.threads),
                                   pipeline_mode});
        loop_ = std::make_unique<FrameLoop>(*pipeline_, script_ ? &*script_ : nullptr);
        loop_->on_script_error = [this](const std::string& message) {
            script_errors_.push_back(message);
        };
    }

public:
    py::dict run(int frames) {
        if (frames < 0) throw py::value_error("frames: expected a count >= 0");
        {
            const BusyGuard busy(*holder_);
            const py::gil_scoped_release release;
            const std::lock_guard<std::mutex> lock(mutex_);
            context_->make_current();
            for (int f = 0; f < frames; ++f) last_ = loop_->step();
            // No photon work is in flight when Python gets the scene back, so it may edit it.
            pipeline_->sync();
        }
        return stats_dict(last_);
    }

    int prime(int max_frames) {
        const BusyGuard busy(*holder_);
        const py::gil_scoped_release release;
        const std::lock_guard<std::mutex> lock(mutex_);
        context_->make_current();
        const int n = pipeline_->prime(max_frames);
        pipeline_->sync();
        return n;
    }

    gpu::FrameImages read_back() {
        const py::gil_scoped_release release;
        const std::lock_guard<std::mutex> lock(mutex_);
        context_->make_current();
        return pipeline_->images();
    }

    py::array_t<float> image(const std::string& component) {
        const std::optional<FrameTerm> term = parse_component(component);
        const gpu::FrameImages images = read_back();
        return to_numpy(term ? images.aov[size_t(*term)] : images.frame);
    }

    py::dict images() {
        const gpu::FrameImages images = read_back();
        py::dict d;
        d["full"] = to_numpy(images.frame);
        for (size_t t = 0; t < kFrameTermNames.size(); ++t)
            d[kFrameTermNames[t]] = to_numpy(images.aov[t]);
        return d;
    }

    std::string renderer() {
        const py::gil_scoped_release release;
        const std::lock_guard<std::mutex> lock(mutex_);
        context_->make_current();
        return context_->renderer();
    }

    SceneRef holder_;
    std::optional<Script> script_;
    std::unique_ptr<gpu::GlContext> context_;
    std::unique_ptr<Pipeline> pipeline_;
    std::unique_ptr<FrameLoop> loop_;
    std::mutex mutex_;
    PipelineStats last_;
    std::vector<std::string> script_errors_;
};

// ---- references ---------------------------------------------------------------------------------

py::dict render_reference(const SceneRef& holder, const std::string& method, std::optional<int> spp,
                          double time, std::optional<int> seed, int threads,
                          std::optional<std::array<int, 2>> size,
                          std::optional<std::array<int, 4>> region, int photons,
                          int caustic_photons, int knn, int caustic_knn, float caustic_radius,
                          int gather_rays, int area_samples) {
    cpu::ReferenceSettings rs;
    if (method == "pt")
        rs.method = cpu::ReferenceMethod::path_tracing;
    else if (method == "pm")
        rs.method = cpu::ReferenceMethod::photon_mapping;
    else
        throw py::value_error("method: expected 'pt' or 'pm', got '" + method + "'");
    Scene scene = holder->scene;  // the camera size may change; the caller's scene stays
    if (size) {
        scene.camera.width = (*size)[0], scene.camera.height = (*size)[1];
        if (scene.camera.width < 1 || scene.camera.height < 1)
            throw py::value_error("size: expected positive (width, height)");
    }
    if (seed && *seed < 0) throw py::value_error("seed: expected a number >= 0");
    rs.seed = uint32_t(seed.value_or(int(scene.settings.seed & 0x7fffffffu)));
    if (time < 0) throw py::value_error("time: expected seconds >= 0");
    rs.time_limit = time;
    const bool pm = rs.method == cpu::ReferenceMethod::photon_mapping;
    rs.spp = spp.value_or(rs.time_limit > 0.0 ? 0 : (pm ? 16 : 64));
    if (rs.spp < 0) throw py::value_error("spp: expected a count >= 0");
    rs.photons = photons;
    rs.caustic_photons = caustic_photons;
    rs.knn = knn;
    rs.caustic_knn = caustic_knn;
    rs.caustic_radius = caustic_radius;
    rs.gather_rays = gather_rays;
    rs.area_light_samples = area_samples;
    if (region) rs.region = {(*region)[0], (*region)[1], (*region)[2], (*region)[3]};
    if (threads < 0) throw py::value_error("threads: expected a count >= 0 (0 = all cores)");
    cpu::ReferenceResult result;
    {
        const py::gil_scoped_release release;
        ThreadPool pool(threads);
        result = cpu::render_reference(scene, rs, pool);
    }
    py::dict d;
    d["full"] = to_numpy(result.full);
    for (size_t t = 0; t < kFrameTermNames.size(); ++t)
        d[kFrameTermNames[t]] = to_numpy(result.components[t]);
    d["spp"] = result.spp;
    d["seconds"] = result.seconds;
    d["photon_seconds"] = result.photon_seconds;
    d["global_photons"] = result.global_photons;
    d["caustic_photons"] = result.caustic_photons;
    d["seed"] = rs.seed;
    return d;
}

// ---- the convergence study ----------------------------------------------------------------------

py::dict converge(const SceneRef& holder, std::optional<std::string> script, int frames,
                  std::array<int, 2> size, const std::string& component,
                  const std::string& baseline, const py::object& reference,
                  const std::string& cache, int ref_spp, int ref_photons,
                  std::optional<int> threads, bool prime, const py::object& settings,
                  const std::string& gl, const py::object& progress) {
    if (frames < 1) throw py::value_error("frames: expected a count >= 1");
    const auto [width, height] = size;
    if (width < 1 || height < 1) throw py::value_error("size: expected positive (width, height)");
    parse_component(component);
    const PipelineMode mode = parse_mode(baseline);
    Scene scene = holder->scene;
    apply_settings(scene, settings);
    scene.camera.width = width;
    scene.camera.height = height;
    const std::string script_path = script ? *script : scene.script;
    const int thread_count = threads.value_or(scene.settings.threads);

    Image reference_image;
    std::string reference_path;
    if (reference.is_none()) {
        cli::ReferenceRequest request;
        request.name = std::filesystem::path(scene.path).stem().string();
        if (request.name.empty()) request.name = "scene";
        request.cache = cache;
        request.spp = ref_spp;
        request.photons = ref_photons;
        request.threads = thread_count;
        request.log_prefix = "afterglow.converge";
        {
            const py::gil_scoped_release release;
            reference_path = cli::cached_reference(scene, script_path, frames, request);
        }
        reference_image = cli::read_reference(reference_path, component, width, height);
    } else if (py::isinstance<py::str>(reference)) {
        reference_path = reference.cast<std::string>();
        reference_image = cli::read_reference(reference_path, component, width, height);
    } else {
        reference_image = to_image(reference, "reference");
        if (reference_image.width != width || reference_image.height != height)
            throw py::value_error("reference: expected a " + std::to_string(width) + "x" +
                                  std::to_string(height) + " image, got " +
                                  std::to_string(reference_image.width) + "x" +
                                  std::to_string(reference_image.height));
    }

    std::function<void(int)> on_frame;
    if (!progress.is_none())
        on_frame = [&progress, frames](int done) {
            const py::gil_scoped_acquire acquire;
            progress(done, frames);
        };
    cli::ConvergenceRun run;
    {
        const py::gil_scoped_release release;
        auto context = gpu::make_gl_context(parse_backend(gl));
        run = cli::run_convergence(scene, script_path, mode, frames, width, height, component,
                                   reference_image, thread_count, prime, on_frame);
    }

    // The columns of `afterglow converge`'s CSV, in its order.
    const std::vector<std::pair<const char*, double (*)(const cli::FrameRecord&)>> columns = {
        {"frame", [](const cli::FrameRecord& r) { return double(r.frame); }},
        {"wall_s", [](const cli::FrameRecord& r) { return r.wall_s; }},
        {"frame_ms", [](const cli::FrameRecord& r) { return r.frame_ms; }},
        {"edited", [](const cli::FrameRecord& r) { return r.edited ? 1.0 : 0.0; }},
        {"relmse", [](const cli::FrameRecord& r) { return r.relmse; }},
        {"rmse", [](const cli::FrameRecord& r) { return r.rmse; }},
        {"ssim", [](const cli::FrameRecord& r) { return r.ssim; }},
        {"groups_invalidated",
         [](const cli::FrameRecord& r) { return double(r.groups_invalidated); }},
        {"photons_retraced", [](const cli::FrameRecord& r) { return double(r.photons_retraced); }},
        {"aim_texels", [](const cli::FrameRecord& r) { return double(r.aim_texels); }},
        {"iim_texels", [](const cli::FrameRecord& r) { return double(r.iim_texels); }},
        {"iim_pending", [](const cli::FrameRecord& r) { return double(r.iim_pending); }},
        {"rays_traced", [](const cli::FrameRecord& r) { return double(r.rays_traced); }},
        {"rays_reused", [](const cli::FrameRecord& r) { return double(r.rays_reused); }},
        {"workers_behind", [](const cli::FrameRecord& r) { return r.workers_behind ? 1.0 : 0.0; }},
    };
    py::dict table;  // insertion-ordered
    for (const auto& [name, get] : columns) {
        py::array_t<double> values(py::ssize_t(run.frames.size()));
        double* out = values.mutable_data();
        for (size_t i = 0; i < run.frames.size(); ++i) out[i] = get(run.frames[i]);
        table[name] = values;
    }
    const cli::SettleAnalysis& s = run.settle;
    py::dict settle;
    settle["settled"] = s.settled;
    settle["first_edit"] = s.first_edit;
    settle["last_edit"] = s.last_edit;
    settle["within"] = s.within;
    settle["frames"] = s.frames;
    settle["seconds"] = s.seconds;
    settle["settled_ok"] = s.settled_ok();
    py::dict d;
    d["method"] = kPipelineModeNames[size_t(run.mode)];
    d["component"] = run.component;
    d["table"] = table;
    d["csv"] = cli::convergence_csv(run);
    d["settle"] = settle;
    d["wall_s"] = run.wall_s;
    d["reference"] = reference_path.empty() ? py::object(py::none()) : py::str(reference_path);
    return d;
}

py::dict metrics_dict(const ImageMetrics& m) {
    py::dict d;
    d["rmse"] = m.rmse;
    d["relmse"] = m.rel_mse;
    d["psnr"] = m.psnr;
    d["ssim"] = m.ssim;
    d["peak"] = m.peak;
    d["pixels"] = m.pixels;
    return d;
}

std::optional<Image> optional_mask(const py::object& mask) {
    if (mask.is_none()) return std::nullopt;
    return to_image(mask, "mask");
}

}  // namespace
}  // namespace ag::python

PYBIND11_MODULE(_afterglow, m) {
    using namespace ag;
    using namespace ag::python;
    m.doc() =
        "Afterglow: progressive global illumination in dynamic scenes (Larsen 2004). Scenes and "
        "their edits, the progressive pipeline, reference renderers, image metrics and "
        "convergence studies. See docs/python.md.";
    m.attr("__version__") = "0.1";

    static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const InputError& e) {
            input_error(e.what());
        }
    });
    input_error.attr("__module__") = "afterglow";
    input_error.doc() =
        "Bad user input (scene files, settings, edits, scripts): the message names the file, the "
        "place and what was expected, as the afterglow command prints it.";

    py::class_<ObjectHandle>(m, "Object",
                             "A scene object (Scene.object(name)); edits go through the same "
                             "scene-edit API as Lua scripts (docs/scripting.md).")
        .def_property_readonly("name", [](const ObjectHandle& o) { return o.get().name; })
        .def_property_readonly("index", [](const ObjectHandle& o) { return o.index; })
        .def_property_readonly(
            "dynamic", [](const ObjectHandle& o) { return o.get().dynamic; },
            "Whether scripts and edits may move it (scene file \"dynamic\": true).")
        .def_property_readonly(
            "position",
            [](const ObjectHandle& o) { return to_tuple(o.get().transform.translation); },
            "World position of the object's origin (x, y, z).")
        .def_property_readonly(
            "rotation",
            [](const ObjectHandle& o) {
                const glm::quat& q = o.get().transform.rotation;
                return std::array<float, 4>{q.w, q.x, q.y, q.z};
            },
            "Rotation quaternion (w, x, y, z).")
        .def_property_readonly(
            "material",
            [](const ObjectHandle& o) {
                const Material& mat = o.get().material;
                py::dict d;
                d["name"] = mat.name;
                d["type"] = kMaterialTypeNames[size_t(mat.type)];
                d["albedo"] = to_tuple(mat.albedo);
                d["ior"] = mat.ior;
                d["emission"] = to_tuple(mat.emission);
                return d;
            },
            "The object's own material: name, type (diffuse, mirror, glass), albedo, ior, "
            "emission.")
        .def_property_readonly(
            "albedo", [](const ObjectHandle& o) { return to_tuple(o.get().material.albedo); })
        .def(
            "set_position",
            [](const ObjectHandle& o, const Vec3& p) {
                Scene& scene = o.holder->for_edit();
                check_movable(scene, o.index, "set_position");
                Transform t = scene.objects[size_t(o.index)].transform;
                t.translation = to_glm(p);
                set_object_transform(scene, o.index, t);
            },
            py::arg("position"), "Moves a dynamic object's origin to `position` (x, y, z).")
        .def(
            "translate",
            [](const ObjectHandle& o, const Vec3& d) {
                Scene& scene = o.holder->for_edit();
                check_movable(scene, o.index, "translate");
                translate_object(scene, o.index, to_glm(d));
            },
            py::arg("offset"), "Moves a dynamic object by `offset` (x, y, z).")
        .def(
            "rotate",
            [](const ObjectHandle& o, const Vec3& axis, float degrees) {
                Scene& scene = o.holder->for_edit();
                check_movable(scene, o.index, "rotate");
                rotate_object(scene, o.index, to_glm(axis), degrees);
            },
            py::arg("axis"), py::arg("degrees"),
            "Rotates a dynamic object about its own origin, `degrees` around the world `axis`.")
        .def(
            "set_albedo",
            [](const ObjectHandle& o, const Vec3& albedo) {
                set_albedo(o.holder->for_edit(), o.index, to_glm(albedo));
            },
            py::arg("albedo"), "Sets the diffuse albedo (r, g, b), each in [0, 1].")
        .def("__repr__",
             [](const ObjectHandle& o) { return "<afterglow.Object '" + o.get().name + "'>"; });

    py::class_<LightHandle>(m, "Light", "A light of the scene (Scene.light(name)).")
        .def_property_readonly("name", [](const LightHandle& l) { return l.get().name; })
        .def_property_readonly("index", [](const LightHandle& l) { return l.index; })
        .def_property_readonly(
            "type", [](const LightHandle& l) { return kLightTypeNames[size_t(l.get().type)]; },
            "point, quad, mesh, sun or spot.")
        .def_property_readonly(
            "position", [](const LightHandle& l) { return to_tuple(l.get().center()); },
            "Position (a quad: its centre; a mesh light: its object's centre).")
        .def_property_readonly(
            "color", [](const LightHandle& l) { return to_tuple(l.get().value()); },
            "Intensity (point, spot), irradiance (sun) or radiance (quad, mesh), RGB.")
        .def_property_readonly("enabled", [](const LightHandle& l) { return l.get().enabled; })
        .def(
            "set_position",
            [](const LightHandle& l, const Vec3& p) {
                set_light_position(l.holder->for_edit(), l.index, to_glm(p));
            },
            py::arg("position"), "Moves the light (a quad: its centre) to `position`.")
        .def(
            "move",
            [](const LightHandle& l, const Vec3& d) {
                Scene& scene = l.holder->for_edit();
                set_light_position(scene, l.index,
                                   scene.lights[size_t(l.index)].center() + to_glm(d));
            },
            py::arg("offset"), "Moves the light by `offset`.")
        .def(
            "set_color",
            [](const LightHandle& l, const Vec3& c) {
                set_light_color(l.holder->for_edit(), l.index, to_glm(c));
            },
            py::arg("color"), "Sets the intensity / irradiance / radiance (RGB, >= 0).")
        .def(
            "set_enabled",
            [](const LightHandle& l, bool enabled) {
                set_light_enabled(l.holder->for_edit(), l.index, enabled);
            },
            py::arg("enabled"), "Switches the light on or off.")
        .def("__repr__",
             [](const LightHandle& l) { return "<afterglow.Light '" + l.get().name + "'>"; });

    py::class_<SceneHolder, SceneRef>(
        m, "Scene",
        "A scene (docs/scene-format.md): objects, lights, camera and settings. Load it with "
        "Scene.load(path) or Scene.from_dict(d); edit it between pipeline runs.")
        .def_static(
            "load",
            [](const std::string& path) {
                auto h = std::make_shared<SceneHolder>();
                h->scene = load_scene(path);
                return h;
            },
            py::arg("path"), "Reads a JSON scene file (InputError naming the file and place).")
        .def_static(
            "from_dict",
            [](const py::dict& d, const std::string& path) {
                auto h = std::make_shared<SceneHolder>();
                h->scene = parse_scene(json_dumps(d), path);
                return h;
            },
            py::arg("scene"), py::arg("path") = "scene.json",
            "Builds a scene from a dict shaped like a scene file; relative mesh and script paths "
            "are resolved against the folder of `path`, which also names the scene in messages.")
        .def_static(
            "from_json",
            [](const std::string& text, const std::string& path) {
                auto h = std::make_shared<SceneHolder>();
                h->scene = parse_scene(text, path);
                return h;
            },
            py::arg("text"), py::arg("path") = "scene.json", "Same as from_dict, from JSON text.")
        .def(
            "copy",
            [](SceneHolder& h) {
                auto c = std::make_shared<SceneHolder>();
                c->scene = h.for_edit();  // not while a pipeline may trim its change log
                return c;
            },
            "An independent copy (edits to one do not reach the other).")
        .def_property_readonly("name", [](const SceneHolder& h) { return h.scene.name; })
        .def_property_readonly("path", [](const SceneHolder& h) { return h.scene.path; })
        .def_property_readonly(
            "script", [](const SceneHolder& h) { return h.scene.script; },
            "The scene's Lua edit script (resolved path), or ''.")
        .def_property_readonly(
            "objects",
            [](const SceneHolder& h) {
                std::vector<std::string> names;
                for (const Object& o : h.scene.objects) names.push_back(o.name);
                return names;
            },
            "Object names, in scene order.")
        .def_property_readonly(
            "lights",
            [](const SceneHolder& h) {
                std::vector<std::string> names;
                for (const Light& l : h.scene.lights) names.push_back(l.name);
                return names;
            },
            "Light names, in scene order (mesh lights are named after their objects).")
        .def_property_readonly(
            "version", [](const SceneHolder& h) { return h.scene.version; },
            "Bumped by every edit.")
        .def_property_readonly("triangles",
                               [](const SceneHolder& h) { return h.scene.triangle_count(); })
        .def(
            "object",
            [](const SceneRef& h, const std::string& name) {
                const int i = h->scene.find_object(name);
                if (i < 0) no_such("object", name, h->scene.objects);
                return ObjectHandle{h, i};
            },
            py::arg("name"), "The object named `name` (InputError listing the names if none).")
        .def(
            "light",
            [](const SceneRef& h, const std::string& name) {
                const int i = h->scene.find_light(name);
                if (i < 0) no_such("light", name, h->scene.lights);
                return LightHandle{h, i};
            },
            py::arg("name"), "The light named `name` (InputError listing the names if none).")
        .def(
            "run_script",
            [](SceneHolder& h, const std::string& path, int frames) {
                Scene& scene = h.for_edit();
                Script script(path);
                const py::gil_scoped_release release;
                run_script_ahead(script, scene, frames);
            },
            py::arg("path"), py::arg("frames"),
            "Runs a Lua edit script on the scene for `frames` frames at 30 frames/s, without a "
            "pipeline: the state at the end of a run (e.g. to render its reference).")
        .def_property_readonly(
            "camera", [](const SceneHolder& h) { return camera_dict(h.scene.camera); },
            "eye, target, up, fov_y (degrees) and resolution (width, height).")
        .def(
            "set_camera",
            [](SceneHolder& h, std::optional<Vec3> eye, std::optional<Vec3> target,
               std::optional<Vec3> up, std::optional<float> fov_y,
               std::optional<std::array<int, 2>> resolution) {
                Scene& scene = h.for_edit();
                Camera c = scene.camera;
                if (eye) c.eye = to_glm(*eye);
                if (target) c.target = to_glm(*target);
                if (up) c.up = to_glm(*up);
                if (fov_y) c.fov_y = *fov_y;
                if (resolution) c.width = (*resolution)[0], c.height = (*resolution)[1];
                set_camera(scene, c);
            },
            py::kw_only(), py::arg("eye") = py::none(), py::arg("target") = py::none(),
            py::arg("up") = py::none(), py::arg("fov_y") = py::none(),
            py::arg("resolution") = py::none(),
            "Changes the camera; arguments left out keep their values.")
        .def_property_readonly(
            "settings",
            [](const SceneHolder& h) {
                return py::module_::import("json").attr("loads")(
                    settings_to_json_value(h.scene.settings).dump());
            },
            "The settings as a dict (the scene file's \"settings\" shape, every field).")
        .def(
            "apply_settings",
            [](SceneHolder& h, const py::dict& settings) {
                apply_settings(h.for_edit(), settings);
            },
            py::arg("settings"),
            "Overwrites the settings the dict holds ({\"photons\": {\"groups\": 64}, \"seed\": "
            "3}); "
            "InputError naming the key and what was expected, the scene unchanged then.")
        .def("__repr__", [](const SceneHolder& h) {
            return "<afterglow.Scene '" + h.scene.name +
                   "': " + std::to_string(h.scene.objects.size()) + " objects, " +
                   std::to_string(h.scene.lights.size()) + " lights>";
        });

    py::class_<PyPipeline>(
        m, "Pipeline",
        "The progressive pipeline (Larsen ch. 6-13) on a scene, headless. Each instance owns its "
        "GL context (OSMesa by default). `settings` (a dict) is applied to the scene first, as "
        "`afterglow render --set` does. Edit the scene between run() calls; the next frame sees "
        "the edits.")
        .def(py::init<SceneRef, py::object, std::optional<std::array<int, 2>>, std::optional<int>,
                      std::string, std::string, std::optional<std::string>>(),
             py::arg("scene"), py::kw_only(), py::arg("settings") = py::none(),
             py::arg("size") = py::none(), py::arg("threads") = py::none(),
             py::arg("mode") = "selective", py::arg("gl") = "osmesa",
             py::arg("script") = py::none(),
             "scene: a Scene; size: (width, height), default the camera's; threads: photon "
             "workers (default settings.threads, 0 = all cores); mode: selective, full or "
             "full-budget; gl: osmesa, egl or auto; script: a Lua edit script (default the "
             "scene's; '' for none).")
        .def("run", &PyPipeline::run, py::arg("frames") = 1,
             "Runs `frames` frames (the GIL released) and returns the last frame's counters.")
        .def("prime", &PyPipeline::prime, py::arg("max_frames") = 64,
             "Brings everything to the converged state of the current scene at once (untimed).")
        .def("image", &PyPipeline::image, py::arg("component") = "full",
             "The last frame (or one term: direct, indirect, caustics, specular, volume) as a "
             "float32 "
             "array (H, W, 3) of linear radiance.")
        .def("images", &PyPipeline::images,
             "The frame and its four terms, a dict of float32 (H, W, 3) arrays.")
        .def_property_readonly(
            "counters", [](const PyPipeline& p) { return stats_dict(p.last_); },
            "The last frame's counters and timings (ms).")
        .def_property_readonly("frame_index",
                               [](const PyPipeline& p) { return p.pipeline_->frame_index(); })
        .def_property_readonly("converged",
                               [](const PyPipeline& p) { return p.pipeline_->converged(); })
        .def_property_readonly("scene", [](const PyPipeline& p) { return p.holder_; })
        .def_property_readonly(
            "script_errors", [](const PyPipeline& p) { return p.script_errors_; },
            "Messages of the script's failed callbacks (rendering went on).")
        .def_property_readonly("renderer", &PyPipeline::renderer,
                               "GL_RENDERER, e.g. 'llvmpipe (LLVM 15.0.6, 256 bits)'.");

    const cpu::ReferenceSettings defaults;
    m.def("render_reference", &render_reference, py::arg("scene"), py::kw_only(),
          py::arg("method") = "pt", py::arg("spp") = py::none(), py::arg("time") = 0.0,
          py::arg("seed") = py::none(), py::arg("threads") = 0, py::arg("size") = py::none(),
          py::arg("region") = py::none(), py::arg("photons") = defaults.photons,
          py::arg("caustic_photons") = defaults.caustic_photons, py::arg("knn") = defaults.knn,
          py::arg("caustic_knn") = defaults.caustic_knn,
          py::arg("caustic_radius") = defaults.caustic_radius,
          py::arg("gather_rays") = defaults.gather_rays,
          py::arg("area_samples") = defaults.area_light_samples,
          "A reference image of the scene's camera, as `afterglow reference`: method pt (path "
          "tracing) or pm (photon mapping); spp (default 64 pt, 16 pm); seed (default the "
          "scene's); size (width, height); region (x, y, width, height): only those pixels, "
          "exactly as they are in the whole image (tiles merge bit-exactly). Returns a dict: "
          "full, direct, indirect, caustics, specular, volume (float32 (H, W, 3)), spp, seconds, "
          "...");

    m.def("converge", &converge, py::arg("scene"), py::kw_only(), py::arg("script") = py::none(),
          py::arg("frames") = 120, py::arg("size") = std::array<int, 2>{96, 96},
          py::arg("component") = "indirect", py::arg("baseline") = "selective",
          py::arg("reference") = py::none(), py::arg("cache") = "out/reference-cache",
          py::arg("ref_spp") = 64, py::arg("ref_photons") = 400000, py::arg("threads") = py::none(),
          py::arg("prime") = false, py::arg("settings") = py::none(), py::arg("gl") = "osmesa",
          py::arg("progress") = py::none(),
          "The convergence study of `afterglow converge`: runs the pipeline (and the edit "
          "script, default the scene's) for `frames` frames and records after each the wall time, "
          "the error of `component` against the reference and the counters. reference: None "
          "(the cached pm reference of the final state), an EXR path, or an (H, W, 3) array. "
          "Returns a dict: table (column name -> numpy array), csv (as the command writes it), "
          "settle (the 10% settle rule), wall_s, method, component, reference.");

    m.def(
        "compare",
        [](const py::object& test, const py::object& reference, const py::object& mask) {
            const Image t = to_image(test, "test"), r = to_image(reference, "reference");
            const std::optional<Image> k = optional_mask(mask);
            return metrics_dict(compare_images(t, r, k ? &*k : nullptr));
        },
        py::arg("test"), py::arg("reference"), py::arg("mask") = py::none(),
        "RMSE, relMSE = mean((x-y)^2/(y^2+0.01)), PSNR and SSIM of `test` against `reference` "
        "(float arrays (H, W, 3)); a dict rmse, relmse, psnr, ssim, peak, pixels.");
    m.def(
        "error_heatmap",
        [](const py::object& test, const py::object& reference, double max_error,
           const py::object& mask) {
            const Image t = to_image(test, "test"), r = to_image(reference, "reference");
            const std::optional<Image> k = optional_mask(mask);
            return to_numpy(relative_error_heatmap(t, r, k ? &*k : nullptr, max_error));
        },
        py::arg("test"), py::arg("reference"), py::arg("max_error") = 1.0,
        py::arg("mask") = py::none(), "Per-pixel relative error as a colour ramp (H, W, 3).");
    m.def(
        "read_image", [](const std::string& path) { return to_numpy(read_image(path)); },
        py::arg("path"), "Any image OpenImageIO reads, as linear float32 (H, W, 3).");
    m.def(
        "write_image",
        [](const py::object& image, const std::string& path, float exposure) {
            write_image(to_image(image, "image"), path, exposure);
        },
        py::arg("image"), py::arg("path"), py::arg("exposure") = 0.0f,
        "Writes .exr (linear) or .png (sRGB, 2^exposure scaling), atomically.");
    m.attr("frame_terms") =
        std::vector<std::string>(kFrameTermNames.begin(), kFrameTermNames.end());
}
