#include "shared/lightmap_sample.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

namespace ag {

namespace {

// The texel itself first, then its 8-neighbours.
constexpr int kAround[9][2] = {{0, 0}, {-1, -1}, {0, -1}, {1, -1}, {-1, 0},
                               {1, 0}, {-1, 1},  {0, 1},  {1, 1}};

bool inside_chart(const Chart& chart, glm::vec2 uv) {
    return uv.x >= float(chart.x) && uv.x < float(chart.x + chart.width) &&
           uv.y >= float(chart.y) && uv.y < float(chart.y + chart.height);
}

size_t atlas_index(const LightmapAtlas& atlas, int x, int y) {
    return size_t(y) * size_t(atlas.width) + size_t(x);
}

// Record index of the chart's texel whose centre is nearest to `uv`, or -1. Only reached when
// none of the four bilinear texels exists, which a point on a chart triangle almost never is.
int nearest_chart_texel(const LightmapAtlas& atlas, int chart_id, glm::vec2 uv) {
    const Chart& chart = atlas.charts[size_t(chart_id)];
    int best = -1;
    float best_d2 = std::numeric_limits<float>::infinity();
    for (int y = chart.y; y < chart.y + chart.height; ++y)
        for (int x = chart.x; x < chart.x + chart.width; ++x) {
            const int r = atlas.texel_at(x, y);
            if (r < 0 || atlas.texels[size_t(r)].chart != chart_id) continue;
            const glm::vec2 d = glm::vec2(float(x) + 0.5f, float(y) + 0.5f) - uv;
            const float d2 = glm::dot(d, d);
            if (d2 < best_d2) best_d2 = d2, best = r;
        }
    return best;
}

enum CellState : char { kNoTexel, kKnown, kUnknown, kQueued };

}  // namespace

glm::vec2 lightmap_uv(const LightmapAtlas& atlas, int object, int triangle, glm::vec2 barycentric) {
    const glm::vec2* c = &atlas.corner_uvs[size_t(object)][3 * size_t(triangle)];
    return (1.0f - barycentric.x - barycentric.y) * c[0] + barycentric.x * c[1] +
           barycentric.y * c[2];
}

int triangle_chart(const LightmapAtlas& atlas, int object, int triangle) {
    if (object < 0 || size_t(object) >= atlas.corner_uvs.size() || triangle < 0) return -1;
    const std::vector<glm::vec2>& uvs = atlas.corner_uvs[size_t(object)];
    const size_t k = 3 * size_t(triangle);
    if (k + 2 >= uvs.size()) return -1;
    // The centroid lies inside the triangle, so the texel holding it overlaps the triangle and
    // has a record of its chart (a sliver's may not: its neighbours are tried). Chart rectangles
    // never overlap and hold all their triangles' UVs, so the rectangle test makes the answer
    // exact, even with gutter 0 (specular objects' UVs are all 0, inside no rectangle).
    const glm::vec2 centroid = (uvs[k] + uvs[k + 1] + uvs[k + 2]) / 3.0f;
    const int cx = int(std::floor(centroid.x)), cy = int(std::floor(centroid.y));
    for (const auto& d : kAround) {
        const int x = cx + d[0], y = cy + d[1];
        if (x < 0 || y < 0 || x >= atlas.width || y >= atlas.height) continue;
        const int r = atlas.texel_at(x, y);
        if (r < 0) continue;
        const TexelRecord& record = atlas.texels[size_t(r)];
        if (record.object == object && inside_chart(atlas.charts[size_t(record.chart)], centroid))
            return record.chart;
    }
    return -1;
}

glm::vec3 sample_lightmap(const LightmapAtlas& atlas, const std::vector<glm::vec3>& texels,
                          int object, int triangle, glm::vec2 barycentric) {
    assert(texels.size() == size_t(atlas.width) * size_t(atlas.height));
    const int chart = triangle_chart(atlas, object, triangle);
    if (chart < 0) return glm::vec3(0.0f);
    const glm::vec2 uv = lightmap_uv(atlas, object, triangle, barycentric);
    // Texel centres sit at integer + ½: the four around uv start at floor(uv - ½).
    const glm::vec2 f = uv - 0.5f;
    const int x0 = int(std::floor(f.x)), y0 = int(std::floor(f.y));
    const float tx = f.x - float(x0), ty = f.y - float(y0);
    glm::vec3 sum(0.0f);
    float weight = 0.0f;
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int x = x0 + dx, y = y0 + dy;
            if (x < 0 || y < 0 || x >= atlas.width || y >= atlas.height) continue;
            const int r = atlas.texel_at(x, y);
            if (r < 0 || atlas.texels[size_t(r)].chart != chart) continue;
            const float w = (dx ? tx : 1.0f - tx) * (dy ? ty : 1.0f - ty);
            sum += w * texels[atlas_index(atlas, x, y)];
            weight += w;
        }
    if (weight > 0.0f) return sum / weight;
    const int r = nearest_chart_texel(atlas, chart, uv);
    if (r < 0) return glm::vec3(0.0f);
    const TexelRecord& record = atlas.texels[size_t(r)];
    return texels[atlas_index(atlas, record.x, record.y)];
}

void repair_invalid_texels(const LightmapAtlas& atlas, std::vector<glm::vec3>& values,
                           const std::vector<char>& valid_per_record) {
    std::vector<int> targets;
    for (size_t r = 0; r < valid_per_record.size(); ++r)
        if (!valid_per_record[r]) targets.push_back(int(r));
    repair_invalid_texels(atlas, values, valid_per_record, targets);
}

void repair_invalid_texels(const LightmapAtlas& atlas, std::vector<glm::vec3>& values,
                           const std::vector<char>& valid_per_record,
                           const std::vector<int>& targets) {
    assert(values.size() == size_t(atlas.width) * size_t(atlas.height));
    assert(valid_per_record.size() == atlas.texels.size());
    // Targets grouped by chart: each chart is filled once in a local grid over its rectangle.
    std::vector<std::pair<int, int>> work;  // (chart, record)
    for (int r : targets)
        if (!valid_per_record[size_t(r)]) work.emplace_back(atlas.texels[size_t(r)].chart, r);
    std::sort(work.begin(), work.end());
    work.erase(std::unique(work.begin(), work.end()), work.end());

    std::vector<char> state;
    std::vector<glm::vec3> local, layer_values;
    std::vector<int> layer, next_layer;
    for (size_t begin = 0; begin < work.size();) {
        const int chart_id = work[begin].first;
        size_t end = begin;
        while (end < work.size() && work[end].first == chart_id) ++end;
        const Chart& chart = atlas.charts[size_t(chart_id)];
        const int w = chart.width, h = chart.height;
        state.assign(size_t(w) * size_t(h), kNoTexel);
        local.assign(state.size(), glm::vec3(0.0f));
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const int r = atlas.texel_at(chart.x + x, chart.y + y);
                if (r < 0 || atlas.texels[size_t(r)].chart != chart_id) continue;
                const size_t i = size_t(y) * size_t(w) + size_t(x);
                if (valid_per_record[size_t(r)]) {
                    state[i] = kKnown;
                    local[i] = values[atlas_index(atlas, chart.x + x, chart.y + y)];
                } else {
                    state[i] = kUnknown;
                }
            }
        auto neighbours = [&](int cell, auto&& visit) {
            const int x = cell % w, y = cell / w;
            for (int k = 1; k < 9; ++k) {
                const int nx = x + kAround[k][0], ny = y + kAround[k][1];
                if (nx >= 0 && ny >= 0 && nx < w && ny < h) visit(ny * w + nx);
            }
        };
        // First layer: unknown texels touching a known one.
        layer.clear();
        for (int i = 0; i < w * h; ++i) {
            if (state[size_t(i)] != kUnknown) continue;
            bool touches = false;
            neighbours(i, [&](int n) { touches = touches || state[size_t(n)] == kKnown; });
            if (touches) {
                state[size_t(i)] = kQueued;
                layer.push_back(i);
            }
        }
        // Each layer reads only texels known before it, so the order within it does not matter.
        while (!layer.empty()) {
            layer_values.assign(layer.size(), glm::vec3(0.0f));
            for (size_t j = 0; j < layer.size(); ++j) {
                glm::vec3 sum(0.0f);
                int count = 0;
                neighbours(layer[j], [&](int n) {
                    if (state[size_t(n)] != kKnown) return;
                    sum += local[size_t(n)];
                    ++count;
                });
                layer_values[j] = sum / float(count);
            }
            for (size_t j = 0; j < layer.size(); ++j) {
                local[size_t(layer[j])] = layer_values[j];
                state[size_t(layer[j])] = kKnown;
            }
            next_layer.clear();
            for (int cell : layer)
                neighbours(cell, [&](int n) {
                    if (state[size_t(n)] != kUnknown) return;
                    state[size_t(n)] = kQueued;
                    next_layer.push_back(n);
                });
            layer.swap(next_layer);
        }
        // Texels never reached (a chart without valid texels) stay 0.
        for (size_t j = begin; j < end; ++j) {
            const TexelRecord& record = atlas.texels[size_t(work[j].second)];
            const size_t i = size_t(record.y - chart.y) * size_t(w) + size_t(record.x - chart.x);
            values[atlas_index(atlas, record.x, record.y)] = local[i];
        }
        begin = end;
    }
}

void add_lookup_coverage(const LightmapAtlas& atlas, glm::vec2 lookup, float weight,
                         std::vector<float>& coverage) {
    if (atlas.width <= 0) return;
    // Crediting only the texel under the lookup left three of four texels of small, far
    // objects (the conference room's chairs) "unseen" and last in the queue.
    auto record_at = [&](int x, int y) {
        return x < 0 || y < 0 || x >= atlas.width || y >= atlas.height ? -1 : atlas.texel_at(x, y);
    };
    const float u = lookup.x - 0.5f, v = lookup.y - 0.5f;
    const float x0 = std::floor(u), y0 = std::floor(v);
    const float fx = u - x0, fy = v - y0;
    const int x = int(x0), y = int(y0);
    const int records[4] = {record_at(x, y), record_at(x + 1, y), record_at(x, y + 1),
                            record_at(x + 1, y + 1)};
    const float weights[4] = {(1.0f - fx) * (1.0f - fy), fx * (1.0f - fy), (1.0f - fx) * fy,
                              fx * fy};
    float sum = 0.0f;
    for (int k = 0; k < 4; ++k) sum += records[k] >= 0 ? weights[k] : 0.0f;
    if (sum <= 0.0f) {
        // Only gutter texels around the lookup: the record under it, as the chart's edge.
        const int under = record_at(int(std::floor(lookup.x)), int(std::floor(lookup.y)));
        if (under >= 0) coverage[size_t(under)] += weight;
        return;
    }
    for (int k = 0; k < 4; ++k)
        if (records[k] >= 0 && weights[k] > 0.0f)
            coverage[size_t(records[k])] += weights[k] / sum * weight;
}

}  // namespace ag
