#include "gpu/surface_albedo.h"

#include <glm/gtc/packing.hpp>
#include <map>

namespace ag::gpu {

const char* const kSurfaceAlbedoGlsl = R"(
// Per object: first texel, width, height, 1 if it reads a texture.
layout(std430, binding = 11) readonly buffer AlbedoTextures { uvec4 albedo_textures[]; };
layout(std430, binding = 12) readonly buffer AlbedoTexels { uvec2 albedo_texels[]; };  // half RGB
layout(std430, binding = 13) readonly buffer BvhTexcoords { vec2 bvh_texcoords[]; };  // 3 a triangle
vec3 albedo_texel(uvec4 t, int x, int y) {
    int w = int(t.y), h = int(t.z);
    x = ((x % w) + w) % w;
    y = ((y % h) + h) % h;
    uvec2 p = albedo_texels[t.x + uint(y) * t.y + uint(x)];
    return vec3(unpackHalf2x16(p.x), unpackHalf2x16(p.y).x);
}
vec3 texture_albedo(uint object, uint index, vec2 b) {
    uvec4 t = albedo_textures[object];
    if (t.w == 0u) return vec3(1.0);
    vec2 uv = (1.0 - b.x - b.y) * bvh_texcoords[3u * index] + b.x * bvh_texcoords[3u * index + 1u] +
              b.y * bvh_texcoords[3u * index + 2u];
    // Texel centres at (i + 1/2) / n, as ag::Texture::sample.
    float u = (uv.x - floor(uv.x)) * float(t.y) - 0.5, v = (uv.y - floor(uv.y)) * float(t.z) - 0.5;
    float fx = floor(u), fy = floor(v);
    int x0 = int(fx), y0 = int(fy);
    float tx = u - fx, ty = v - fy;
    return (1.0 - ty) * ((1.0 - tx) * albedo_texel(t, x0, y0) + tx * albedo_texel(t, x0 + 1, y0)) +
           ty * ((1.0 - tx) * albedo_texel(t, x0, y0 + 1) + tx * albedo_texel(t, x0 + 1, y0 + 1));
}
)";

void SurfaceAlbedo::upload(const Scene& scene, const FlatBvh& bvh) {
    std::vector<glm::uvec4> textures(std::max<size_t>(scene.objects.size(), 1), glm::uvec4(0));
    std::vector<glm::uvec2> texels;
    std::map<const ag::Texture*, uint32_t> first;
    bool any = false;
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        const Object& obj = scene.objects[o];
        const Material& m = obj.material;
        // Without texture coordinates base_albedo already holds the texture's mean.
        if (!m.albedo_map || m.type != MaterialType::diffuse || !obj.mesh.has_texcoords() ||
            m.albedo_map->texels.empty())
            continue;
        const ag::Texture& t = *m.albedo_map;
        auto [at, fresh] = first.emplace(&t, uint32_t(texels.size()));
        if (fresh)
            for (const glm::vec3& c : t.texels)
                texels.push_back({glm::packHalf2x16(glm::vec2(c.r, c.g)),
                                  glm::packHalf2x16(glm::vec2(c.b, 0.0f))});
        textures[o] = {at->second, uint32_t(t.width), uint32_t(t.height), 1u};
        any = true;
    }
    std::vector<glm::vec2> texcoords;
    if (any) {
        texcoords.assign(3 * bvh.triangles.size(), glm::vec2(0.0f));
        for (size_t i = 0; i < bvh.triangles.size(); ++i) {
            const BvhTriangle& b = bvh.triangles[i];
            if (textures[b.object].w == 0u) continue;
            const Mesh& mesh = scene.objects[b.object].mesh;
            for (size_t k = 0; k < 3; ++k)
                texcoords[3 * i + k] = mesh.texcoords[3 * size_t(b.triangle) + k];
        }
    }
    if (texels.empty()) texels.emplace_back(0u);
    if (texcoords.empty()) texcoords.emplace_back(0.0f);
    textures_ = make_storage_buffer(textures.size() * sizeof(glm::uvec4), textures.data());
    texels_ = make_storage_buffer(texels.size() * sizeof(glm::uvec2), texels.data());
    texcoords_ = make_storage_buffer(texcoords.size() * sizeof(glm::vec2), texcoords.data());
    bytes_ = textures.size() * sizeof(glm::uvec4) + texels.size() * sizeof(glm::uvec2) +
             texcoords.size() * sizeof(glm::vec2);
    check_gl("SurfaceAlbedo::upload");
}

void SurfaceAlbedo::bind() const {
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kAlbedoTexturesBinding, textures_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kAlbedoTexelsBinding, texels_.get());
    gl::BindBufferBase(GL_SHADER_STORAGE_BUFFER, kBvhTexcoordsBinding, texcoords_.get());
}

}  // namespace ag::gpu
