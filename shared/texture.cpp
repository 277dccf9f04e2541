#include "shared/texture.h"

#include <algorithm>
#include <cmath>

#include "shared/image.h"
#include "shared/input_error.h"

namespace ag {

namespace {

int wrap(int i, int n) {
    const int r = i % n;
    return r < 0 ? r + n : r;
}

}  // namespace

glm::vec3 Texture::sample(glm::vec2 uv) const {
    if (texels.empty()) return glm::vec3(1.0f);
    // Texel centres sit at (i + ½) / n; wrap the fractional coordinate first so that huge
    // coordinates keep their precision.
    const float u = (uv.x - std::floor(uv.x)) * float(width) - 0.5f;
    const float v = (uv.y - std::floor(uv.y)) * float(height) - 0.5f;
    if (!std::isfinite(u) || !std::isfinite(v)) return mean;
    const float fx = std::floor(u), fy = std::floor(v);
    const int x0 = int(fx), y0 = int(fy);
    const float tx = u - fx, ty = v - fy;
    auto at = [&](int x, int y) {
        return texels[size_t(wrap(y, height)) * size_t(width) + size_t(wrap(x, width))];
    };
    return (1.0f - ty) * ((1.0f - tx) * at(x0, y0) + tx * at(x0 + 1, y0)) +
           ty * ((1.0f - tx) * at(x0, y0 + 1) + tx * at(x0 + 1, y0 + 1));
}

glm::vec3 Texture::box_mean(glm::vec2 uv0, glm::vec2 uv1, int n) const {
    n = std::max(1, n);
    glm::vec3 sum(0.0f);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            sum += sample(glm::mix(
                uv0, uv1, glm::vec2((float(i) + 0.5f) / float(n), (float(j) + 0.5f) / float(n))));
    return sum / float(n * n);
}

std::shared_ptr<const Texture> load_texture(const std::string& path) {
    const Image image = read_image(path);
    if (image.width <= 0 || image.height <= 0 || image.channels <= 0)
        throw_input_error(path, "", "expected an image with at least one pixel and channel");
    auto texture = std::make_shared<Texture>();
    texture->path = path;
    texture->width = image.width;
    texture->height = image.height;
    texture->texels.resize(size_t(image.width) * size_t(image.height));
    glm::dvec3 sum(0.0);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const float* p = image.at(x, y);
            glm::vec3 c = image.channels >= 3 ? glm::vec3(p[0], p[1], p[2]) : glm::vec3(p[0]);
            for (int k = 0; k < 3; ++k)
                c[k] = std::isfinite(c[k]) ? std::clamp(c[k], 0.0f, 1.0f) : 0.0f;
            // Images are stored top row first; texture rows bottom first.
            texture->texels[size_t(image.height - 1 - y) * size_t(image.width) + size_t(x)] = c;
            sum += glm::dvec3(c);
        }
    texture->mean = glm::vec3(sum / double(texture->texels.size()));
    return texture;
}

std::shared_ptr<const Texture> TextureCache::get(const std::string& path) {
    auto it = loaded_.find(path);
    if (it != loaded_.end()) return it->second;
    auto texture = load_texture(path);
    loaded_.emplace(path, texture);
    return texture;
}

}  // namespace ag
