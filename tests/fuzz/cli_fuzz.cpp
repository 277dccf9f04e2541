// Fuzz target: the command line (tools/afterglow/cli) without running a command. The input, split
// at newlines, is the argument list of a command declaring one option of every kind the real
// commands use; what parses is read back through every getter and applied to the Cornell box's
// settings (--gather, --indirect, --frame-ms, --set, rebuilding the atlas where --set changes it).
#include <vector>

#include "gpu/gl_context.h"
#include "shared/scene_file.h"
#include "tests/fuzz/fuzz_input.h"
#include "tools/afterglow/cli.h"

namespace {

using namespace ag::cli;

const Command& command() {
    static const Command c{
        "fuzz",
        "SCENE [MORE] [options]",
        "Every kind of option.",
        {
            text("output,o", "OUT.exr", "output"),
            integer("frames,n", "N", "frames", 1, 1000000, 30),
            size_option("image size"),
            flag("aov", "a flag"),
            gl_option({ag::gpu::GlBackend::osmesa, ag::gpu::GlBackend::egl,
                       ag::gpu::GlBackend::automatic},
                      ag::gpu::GlBackend::osmesa),
            gather_option(),
            indirect_option(),
            frame_ms_option(),
            settings_option(),
            number("exposure", "EV", "exposure", -100, 100, 0),
            integer("threads", "N", "threads", 0, 1024),
            choice("method,m", "M", "method:", {"pt", "pm"}, "pt"),
            flag("quiet,q", "no progress"),
        },
        1,
        2,
    };
    return c;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const ag::Scene cornell = ag::load_scene(AG_SOURCE_DIR "/scenes/cornell.json");
    const std::string input = ag::fuzz::as_string(data, size);
    std::vector<std::string> argv;
    for (size_t start = 0; start <= input.size();) {
        const size_t end = std::min(input.find('\n', start), input.size());
        argv.push_back(input.substr(start, end - start));
        start = end + 1;
    }
    try {
        const Args args(command(), argv);
        if (args.help()) {
            (void)help_text(command());
            return 0;
        }
        (void)args.get("output");
        (void)args.get_int("frames");
        (void)args.get_int("threads", 0);
        (void)args.get_double("exposure");
        (void)args.get_double("frame-ms", 0.0);
        (void)args.get_choice("method");
        (void)args.gl_backend();
        int width = 64, height = 64;
        args.get_size("size", width, height);
        ag::Scene scene = cornell;
        ag::fuzz::expect_input_errors_only([&] { args.apply_settings(scene); });
    } catch (const CliError&) {
    }
    return 0;
}
