// afterglow bench soak SCENE: a long run of random edits, looking for anything that grows (memory,
// frame time, the scene's change log) once the pipeline has reached its working state.
#include "tools/afterglow/bench_soak.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <vector>

#include "gpu/gl_context.h"
#include "shared/input_error.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "tools/afterglow/convergence.h"

namespace ag::cli {

namespace {

struct Sample {
    int frame = 0;
    double rss_mib = 0.0;
    double frame_ms = 0.0;  // mean over the frames since the last sample
    size_t change_log = 0;  // the scene's change log after the frame
};

}  // namespace

int bench_soak(const Args& args, const std::string& scene_path, int size) {
    using Clock = std::chrono::steady_clock;
    const int frames = args.get_int("frames", 100000);
    const std::string csv = args.get("csv", "out/bench-soak.csv");
    auto context = gpu::make_gl_context(args.gl_backend());
    Scene scene = load_scene(scene_path);
    args.apply_settings(scene);
    std::vector<int> movers;
    std::vector<glm::vec3> homes;
    for (int o = 0; o < int(scene.objects.size()); ++o)
        if (scene.objects[size_t(o)].dynamic) {
            movers.push_back(o);
            homes.push_back(scene.objects[size_t(o)].transform.translation);
        }
    if (movers.empty() && scene.lights.empty())
        throw InputError(scene_path + ": bench soak needs a dynamic object or a light to edit");
    const glm::vec3 light_value = scene.lights.empty() ? glm::vec3(0.0f) : scene.lights[0].value();

    Pipeline pipeline(scene, PipelineOptions{size, size});
    FrameLoop loop(pipeline);
    // Moves within a tenth of the scene's diagonal of each object's start, so nothing leaves the
    // room; the same sequence on every run (fixed seed).
    std::mt19937 rng(1);
    const float reach = 0.1f * scene.diagonal();
    std::uniform_real_distribution<float> offset(-reach, reach);
    const int every = std::max(1, frames / 1000);
    const int reference = std::min(10000, std::max(1, frames / 10));
    std::vector<Sample> samples;
    size_t max_log = 0;
    double interval_ms = 0.0;
    std::printf(
        "bench soak: %s, %dx%d, %d frames; %zu objects moved and light 0's colour toggled "
        "every frame\n",
        scene_path.c_str(), size, size, frames, movers.size());
    for (int f = 1; f <= frames; ++f) {
        const Clock::time_point t = Clock::now();
        loop.begin_edits();
        for (size_t m = 0; m < movers.size(); ++m) {
            Transform tr = scene.objects[size_t(movers[m])].transform;
            tr.translation = homes[m] + glm::vec3(offset(rng), 0.0f, offset(rng));
            set_object_transform(scene, movers[m], tr);
        }
        if (!scene.lights.empty())
            set_light_color(scene, 0, f % 2 ? 0.5f * light_value : light_value);
        max_log = std::max(max_log, scene.changes.size());  // this frame's edits included
        loop.step();
        interval_ms += std::chrono::duration<double, std::milli>(Clock::now() - t).count();
        if (f % every == 0 || f == frames || f == reference) {
            const int since = samples.empty() ? f : f - samples.back().frame;
            samples.push_back({f, resident_bytes() / (1024.0 * 1024.0), interval_ms / since,
                               scene.changes.size()});
            interval_ms = 0.0;
        }
    }

    if (const std::filesystem::path dir = std::filesystem::path(csv).parent_path(); !dir.empty())
        std::filesystem::create_directories(dir);
    std::ofstream out(csv);
    if (!out) throw InputError(csv + ": cannot write the CSV");
    out << "frame,rss_mib,frame_ms,change_log\n";
    for (const Sample& s : samples)
        out << s.frame << "," << s.rss_mib << "," << s.frame_ms << "," << s.change_log << "\n";
    const Sample* at_reference = &samples.front();
    for (const Sample& s : samples)
        if (s.frame == reference) at_reference = &s;
    const Sample& last = samples.back();
    // Frame time: the mean over the first and last tenth of the samples after the reference.
    auto mean_ms = [&](size_t from, size_t to) {
        double sum = 0.0;
        for (size_t i = from; i < to; ++i) sum += samples[i].frame_ms;
        return to > from ? sum / double(to - from) : 0.0;
    };
    const size_t first = size_t(at_reference - samples.data());
    const size_t tenth = std::max<size_t>(1, (samples.size() - first) / 10);
    std::printf(
        "RSS %.2f MiB at frame %d, %.2f MiB at frame %d: %+.3f%%\n"
        "frame time %.3f ms after frame %d, %.3f ms at the end\n"
        "change log: %zu entries after the last frame, at most %zu before a frame\n"
        "CSV: %s\n",
        at_reference->rss_mib, at_reference->frame, last.rss_mib, last.frame,
        100.0 * (last.rss_mib / at_reference->rss_mib - 1.0), mean_ms(first, first + tenth),
        at_reference->frame, mean_ms(samples.size() - tenth, samples.size()), last.change_log,
        max_log, csv.c_str());
    return 0;
}

}  // namespace ag::cli
