// Tests that need a GL context: OSMesa by default (AG_TEST_GL=egl picks EGL). Where no context
// can be made the test is reported as skipped, never passed.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>

#include "gpu/gl_context.h"

namespace ag::test {

class GlTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        if (context_ || !error_.empty()) return;
        const char* env = std::getenv("AG_TEST_GL");
        try {
            context_ = gpu::make_gl_context(gpu::parse_gl_backend(env ? env : "osmesa"));
        } catch (const std::exception& e) {
            error_ = e.what();
        }
    }
    void SetUp() override {
        if (!context_) GTEST_SKIP() << "no GL context: " << error_;
        context_->make_current();
    }
    static inline std::unique_ptr<gpu::GlContext> context_;
    static inline std::string error_;
};

}  // namespace ag::test
