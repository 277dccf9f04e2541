// Albedo textures for compute shaders that walk the flat BVH (gpu/gpu_bvh.h): every object's
// albedo texture as half-float texels in one storage buffer, each BVH triangle's corner texture
// coordinates beside it, and kSurfaceAlbedoGlsl, the albedo at a BVH hit, bilinear with wrapping
// exactly as ag::Texture::sample (shared/texture.h) reads it on the CPU.
#pragma once

#include "gpu/gl_objects.h"
#include "shared/flat_bvh.h"
#include "shared/scene.h"
#include "shared/texture.h"

namespace ag::gpu {

// Storage-buffer bindings (the BVH uses 6 and 7; gpu_pm 0–5 and 8–10).
inline constexpr GLuint kAlbedoTexturesBinding = 11, kAlbedoTexelsBinding = 12,
                        kBvhTexcoordsBinding = 13;

// `vec3 texture_albedo(uint object, uint index, vec2 barycentric)`: the texture's value at a hit
// on BVH triangle `index` of `object` (barycentric = (u, v) of v1 and v2), to multiply the
// object's base_albedo by; 1 for an object that reads no texture.
extern const char* const kSurfaceAlbedoGlsl;

class SurfaceAlbedo {
public:
    // Uploads the textures of the scene's diffuse objects that have texture coordinates (each
    // texture once) and the corner coordinates in the BVH's triangle order.
    void upload(const Scene& scene, const FlatBvh& bvh);
    void bind() const;
    size_t bytes() const { return bytes_; }

private:
    Buffer textures_, texels_, texcoords_;
    size_t bytes_ = 0;
};

}  // namespace ag::gpu
