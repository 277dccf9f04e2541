// afterglow glinfo [--gl BACKEND]: which GL context a backend gives (for reports and bug hunts).
#include <iostream>

#include "gpu/gl_context.h"
#include "tools/afterglow/commands.h"

namespace ag::cli {

const Command kGlinfoCommand{
    "glinfo",
    "[--gl auto|osmesa|egl|window]",
    "Create a GL 4.5 core context with the chosen backend and print its renderer and version.",
    {gl_option({gpu::GlBackend::osmesa, gpu::GlBackend::egl, gpu::GlBackend::automatic,
                gpu::GlBackend::window},
               gpu::GlBackend::osmesa)},
    0,
    0,
};

int run_glinfo(const Args& args) {
    auto context = gpu::make_gl_context(args.gl_backend());
    std::cout << "backend  " << gpu::kGlBackendNames[size_t(context->backend())] << "\n"
              << "renderer " << context->renderer() << "\n"
              << "version  " << context->version() << "\n";
    return 0;
}

static const Registration kRegistration(kGlinfoCommand, run_glinfo, 80);

}  // namespace ag::cli
