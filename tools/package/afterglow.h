// Afterglow as a library (find_package(Afterglow), target Afterglow::afterglow): one header for
// the pipeline, scenes and their edits, references, metrics and the convergence study.
#pragma once

#include "cpu/reference/reference.h"
#include "gpu/gl_context.h"
#include "shared/frame_terms.h"
#include "shared/image.h"
#include "shared/input_error.h"
#include "shared/metrics.h"
#include "shared/pipeline/frame_loop.h"
#include "shared/pipeline/pipeline.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "shared/script.h"
#include "tools/afterglow/convergence.h"

namespace ag {

// The library's version, "MAJOR.MINOR" (the project's).
const char* library_version();

}  // namespace ag
