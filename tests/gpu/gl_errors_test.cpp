// GL errors left pending by work that failed (gpu/gl.h, take_gl_errors): compare-methods runs
// every variant on one context, and a variant that threw before reading an error it caused made
// the next variant fail at its first check_gl.
#include <gtest/gtest.h>

#include "gl_fixture.h"
#include "gpu/gl.h"
#include "gpu/gl_objects.h"

namespace ag::gpu {
namespace {

using GlErrors = test::GlTest;

constexpr GLenum kNotACapability = 0x7FFF;  // glEnable(it): GL_INVALID_ENUM

TEST_F(GlErrors, AnErrorLeftPendingFailsTheNextCheckUntilTaken) {
    ASSERT_EQ(take_gl_errors(), "");
    // A failed variant: it caused an error and threw before its check_gl.
    gl::Enable(kNotACapability);
    // The next variant inherits it (what compare-methods did before it took the errors).
    EXPECT_THROW(check_gl("the next variant"), GlError);

    gl::Enable(kNotACapability);
    EXPECT_EQ(take_gl_errors(), "0x0500");  // GL_INVALID_ENUM, named
    EXPECT_NO_THROW(check_gl("the next variant"));
    EXPECT_EQ(take_gl_errors(), "");
}

// check_gl names the error, and a texture the implementation refuses is named with its size: a
// render at --size 16384x16384 on llvmpipe said only "OpenGL error 0x0505 in make_float_texture".
TEST_F(GlErrors, ARefusedTextureIsNamedWithItsErrorAndSize) {
    ASSERT_EQ(take_gl_errors(), "");
    try {
        make_float_texture(-1, 2);  // a negative width: GL_INVALID_VALUE
        FAIL() << "expected a GlError";
    } catch (const GlError& e) {
        EXPECT_NE(
            std::string(e.what()).find(
                "OpenGL error 0x0501 (GL_INVALID_VALUE) in make_float_texture (-1 x 2 RGBA32F"),
            std::string::npos)
            << e.what();
    }
    EXPECT_EQ(take_gl_errors(), "");
}

TEST_F(GlErrors, EveryPendingErrorIsTaken) {
    gl::Enable(kNotACapability);
    gl::Viewport(0, 0, -1, -1);  // GL_INVALID_VALUE: held too where a driver keeps one per kind
    const std::string taken = take_gl_errors();
    EXPECT_EQ(taken.rfind("0x0500", 0), 0u) << taken;
    EXPECT_EQ(gl::GetError(), GLenum(GL_NO_ERROR));
}

}  // namespace
}  // namespace ag::gpu
