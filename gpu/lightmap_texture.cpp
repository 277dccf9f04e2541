#include "gpu/lightmap_texture.h"

#include <algorithm>

namespace ag::gpu {

LightmapTexture::LightmapTexture(const LightmapAtlas& atlas) : atlas_(atlas) {
    const int w = std::max(1, atlas.width), h = std::max(1, atlas.height);
    rgba_.assign(size_t(w) * size_t(h) * 4, 0.0f);
    for (size_t i = 3; i < rgba_.size(); i += 4) rgba_[i] = 1.0f;
    texture_ = make_float_texture(w, h, false, rgba_.data());
    gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    std::vector<float> charts(size_t(w) * size_t(h) * 4, -1.0f);
    for (const TexelRecord& t : atlas.texels)
        charts[(size_t(t.y) * size_t(w) + size_t(t.x)) * 4] = float(t.chart);
    charts_ = make_float_texture(w, h, false, charts.data());
    gutter_of_.resize(size_t(w) * size_t(h));
    sources_of_.resize(size_t(w) * size_t(h));
    if (atlas.texel_index.empty()) return;
    // Padded chart rectangles are disjoint, so an unused texel's used 8-neighbours all belong to
    // one chart: averaging them never mixes charts.
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (atlas.texel_at(x, y) >= 0) continue;
            const int self = y * w + x;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
                    if (atlas.texel_at(nx, ny) < 0) continue;
                    sources_of_[size_t(self)].push_back(ny * w + nx);
                    gutter_of_[size_t(ny * w + nx)].push_back(self);
                }
        }
}

void LightmapTexture::update_all(const std::vector<glm::vec3>& values) {
    std::vector<int> all;
    for (int i = 0; i < atlas_.width * atlas_.height; ++i)
        if (atlas_.texel_index[size_t(i)] >= 0) all.push_back(i);
    update(values, all);
}

void LightmapTexture::update(const std::vector<glm::vec3>& values,
                             const std::vector<int>& changed) {
    if (changed.empty()) return;
    const int w = atlas_.width;
    int x0 = w, y0 = atlas_.height, x1 = -1, y1 = -1;
    auto touch = [&](int i) {
        x0 = std::min(x0, i % w), x1 = std::max(x1, i % w);
        y0 = std::min(y0, i / w), y1 = std::max(y1, i / w);
    };
    for (int i : changed) {
        for (int c = 0; c < 3; ++c) rgba_[4 * size_t(i) + size_t(c)] = values[size_t(i)][c];
        touch(i);
    }
    for (int i : changed)
        for (int g : gutter_of_[size_t(i)]) {
            glm::vec3 sum(0.0f);
            for (int s : sources_of_[size_t(g)])
                sum += glm::vec3(rgba_[4 * size_t(s)], rgba_[4 * size_t(s) + 1],
                                 rgba_[4 * size_t(s) + 2]);
            sum /= float(sources_of_[size_t(g)].size());
            for (int c = 0; c < 3; ++c) rgba_[4 * size_t(g) + size_t(c)] = sum[c];
            touch(g);
        }
    // Upload the changed rectangle row by row from the mirror.
    gl::BindTexture(GL_TEXTURE_2D, texture_.get());
    gl::PixelStorei(GL_UNPACK_ALIGNMENT, 4);
    for (int y = y0; y <= y1; ++y)
        gl::TexSubImage2D(GL_TEXTURE_2D, 0, x0, y, x1 - x0 + 1, 1, GL_RGBA, GL_FLOAT,
                          &rgba_[(size_t(y) * size_t(w) + size_t(x0)) * 4]);
    uploaded_ += size_t(x1 - x0 + 1) * size_t(y1 - y0 + 1);
    check_gl("LightmapTexture::update");
}

}  // namespace ag::gpu
