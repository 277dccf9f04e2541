#include "gpu/scene_meshes.h"

#include "shared/lightmap_sample.h"

namespace ag::gpu {

SceneMeshes::SceneMeshes(const Scene& scene) {
    const LightmapAtlas& atlas = scene.atlas;
    const glm::vec2 atlas_size(std::max(1, atlas.width), std::max(1, atlas.height));
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        const Mesh& mesh = scene.objects[o].mesh;
        std::vector<float> data;
        data.reserve(mesh.triangles.size() * 3 * 9);
        const bool has_uv =
            o < atlas.corner_uvs.size() && atlas.corner_uvs[o].size() == 3 * mesh.triangles.size();
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const glm::vec3 n = triangle_normal(mesh, int(t));
            const float chart = has_uv ? float(triangle_chart(atlas, int(o), int(t))) : -1.0f;
            for (int k = 0; k < 3; ++k) {
                const glm::vec3 p = mesh.positions[mesh.triangles[t][k]];
                const glm::vec2 uv =
                    has_uv ? atlas.corner_uvs[o][3 * t + size_t(k)] / atlas_size : glm::vec2(0.0f);
                data.insert(data.end(), {p.x, p.y, p.z, n.x, n.y, n.z, uv.x, uv.y, chart});
            }
        }
        GpuObject g;
        g.vao = make_vertex_array();
        g.vbo = make_buffer();
        g.triangles = int(mesh.triangles.size());
        gl::BindVertexArray(g.vao.get());
        gl::BindBuffer(GL_ARRAY_BUFFER, g.vbo.get());
        gl::BufferData(GL_ARRAY_BUFFER, GLsizeiptr(data.size() * sizeof(float)), data.data(),
                       GL_STATIC_DRAW);
        const GLsizei stride = 9 * sizeof(float);
        gl::EnableVertexAttribArray(0);
        gl::VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(0));
        gl::EnableVertexAttribArray(1);
        gl::VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride,
                                reinterpret_cast<void*>(3 * sizeof(float)));
        gl::EnableVertexAttribArray(2);
        gl::VertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, stride,
                                reinterpret_cast<void*>(6 * sizeof(float)));
        gl::EnableVertexAttribArray(3);
        gl::VertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, stride,
                                reinterpret_cast<void*>(8 * sizeof(float)));
        objects_.push_back(std::move(g));
    }
    gl::BindVertexArray(0);
    check_gl("SceneMeshes upload");
}

void SceneMeshes::draw(size_t i) const {
    gl::BindVertexArray(objects_[i].vao.get());
    gl::DrawArrays(GL_TRIANGLES, 0, objects_[i].triangles * 3);
}

void SceneMeshes::draw_instanced(size_t i, int instances) const {
    gl::BindVertexArray(objects_[i].vao.get());
    gl::DrawArraysInstanced(GL_TRIANGLES, 0, objects_[i].triangles * 3, instances);
}

}  // namespace ag::gpu
