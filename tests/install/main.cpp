// install_example SCENE: loads a scene through the installed library, runs the progressive
// pipeline for a few frames, moves the cube, renders a path-traced reference and compares.
// Exit 77 (skipped) where no GL context can be made.
#include <afterglow.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: install_example SCENE\n");
        return 2;
    }
    try {
        ag::Scene scene = ag::load_scene(argv[1]);
        std::unique_ptr<ag::gpu::GlContext> context;
        try {
            context = ag::gpu::make_gl_context(ag::gpu::GlBackend::osmesa);
        } catch (const std::exception& e) {
            std::printf("no GL context (%s): skipped\n", e.what());
            return 77;
        }
        ag::Pipeline pipeline(scene, ag::PipelineOptions{24, 24, 1});
        ag::run_frames(pipeline, nullptr, 3);
        pipeline.sync();
        ag::translate_object(scene, scene.find_object("cube"), {40.0f, 0.0f, 0.0f});
        const ag::PipelineStats stats = ag::run_frames(pipeline, nullptr, 1);  // the move is seen
        const ag::Image frame = pipeline.images().frame;

        ag::cpu::ReferenceSettings rs;
        rs.spp = 2;
        ag::Scene copy = scene;
        copy.camera.width = copy.camera.height = 24;
        ag::ThreadPool pool(1);
        const ag::cpu::ReferenceResult reference = ag::cpu::render_reference(copy, rs, pool);
        const ag::ImageMetrics m = ag::compare_images(frame, reference.full);
        std::printf("afterglow %s: %d groups invalidated by the move; relMSE against pt %.4f\n",
                    ag::library_version(), stats.photons.groups_invalidated, m.rel_mse);
        return stats.photons.groups_invalidated > 0 && m.rel_mse > 0.0 ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "install_example: error: %s\n", e.what());
        return 1;
    }
}
