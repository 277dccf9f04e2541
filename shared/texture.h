// Albedo textures (map_Kd, glTF baseColorTexture, scene-file "albedo_map"): linear RGB texels
// read through OpenImageIO (shared/image.h decodes 8- and 16-bit files from sRGB), sampled
// bilinearly with repeat wrapping. Texture coordinates follow OBJ and OpenGL: (0, 0) is the
// bottom-left corner of the image (glTF's top-left origin is flipped when it is read).
#pragma once

#include <glm/glm.hpp>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace ag {

struct Texture {
    std::string path;
    int width = 0, height = 0;
    std::vector<glm::vec3> texels;  // row-major, bottom row first (texel (x, y) at v = (y+½)/h)
    glm::vec3 mean{0.0f};           // of all texels

    // Bilinear between the four nearest texel centres, wrapping at the edges.
    glm::vec3 sample(glm::vec2 uv) const;
    // Mean over the axis-aligned box [uv0, uv1] in texture space, by n × n bilinear samples.
    glm::vec3 box_mean(glm::vec2 uv0, glm::vec2 uv1, int n) const;
};

// Reads an image file as an albedo texture: RGB kept (grey replicated, alpha dropped) and
// clamped to [0, 1] (albedo is a reflectance). Throws InputError naming the file if it cannot be
// read or is empty.
std::shared_ptr<const Texture> load_texture(const std::string& path);

// Loads each file once (materials of one model share textures).
class TextureCache {
public:
    std::shared_ptr<const Texture> get(const std::string& path);

private:
    std::map<std::string, std::shared_ptr<const Texture>> loaded_;
};

}  // namespace ag
