#include "gpu/scene_meshes.h"

#include <map>

#include "shared/lightmap_sample.h"

namespace ag::gpu {

SceneMeshes::SceneMeshes(const Scene& scene) {
    const LightmapAtlas& atlas = scene.atlas;
    std::map<const ag::Texture*, int> uploaded;
    const glm::vec2 atlas_size(std::max(1, atlas.width), std::max(1, atlas.height));
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        const Mesh& mesh = scene.objects[o].mesh;
        std::vector<float> data;
        data.reserve(mesh.triangles.size() * 3 * 11);
        const bool has_uv =
            o < atlas.corner_uvs.size() && atlas.corner_uvs[o].size() == 3 * mesh.triangles.size();
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const glm::vec3 n = triangle_normal(mesh, int(t));
            const float chart = has_uv ? float(triangle_chart(atlas, int(o), int(t))) : -1.0f;
            for (int k = 0; k < 3; ++k) {
                const glm::vec3 p = mesh.positions[mesh.triangles[t][k]];
                const glm::vec2 uv =
                    has_uv ? atlas.corner_uvs[o][3 * t + size_t(k)] / atlas_size : glm::vec2(0.0f);
                const glm::vec2 tc =
                    mesh.has_texcoords() ? mesh.texcoords[3 * t + size_t(k)] : glm::vec2(0.0f);
                data.insert(data.end(),
                            {p.x, p.y, p.z, n.x, n.y, n.z, uv.x, uv.y, chart, tc.x, tc.y});
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
        const GLsizei stride = 11 * sizeof(float);
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
        gl::EnableVertexAttribArray(4);
        gl::VertexAttribPointer(4, 2, GL_FLOAT, GL_FALSE, stride,
                                reinterpret_cast<void*>(9 * sizeof(float)));
        const Material& m = scene.objects[o].material;
        if (m.albedo_map && m.type == MaterialType::diffuse) {
            g.uniform_albedo = !mesh.has_texcoords();
            auto [it, fresh] = uploaded.emplace(m.albedo_map.get(), int(textures_.size()));
            if (fresh) {
                const ag::Texture& t = *m.albedo_map;
                Texture tex = make_texture();
                gl::BindTexture(GL_TEXTURE_2D, tex.get());
                gl::PixelStorei(GL_UNPACK_ALIGNMENT, 4);
                // Rows bottom first, as GL's t = 0 row.
                gl::TexImage2D(GL_TEXTURE_2D, 0, GL_RGB16F, t.width, t.height, 0, GL_RGB, GL_FLOAT,
                               t.texels.data());
                gl::GenerateMipmap(GL_TEXTURE_2D);
                gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
                gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
                gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
                gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
                textures_.push_back(std::move(tex));
            }
            g.albedo_map = it->second;
        }
        objects_.push_back(std::move(g));
    }
    gl::BindVertexArray(0);
    check_gl("SceneMeshes upload");
}

void SceneMeshes::bind_albedo(const Program& program, size_t i, int unit) const {
    const GpuObject& g = objects_[i];
    const bool textured = g.albedo_map >= 0 && !g.uniform_albedo;
    program.set("has_albedo_map", textured ? 1 : 0);
    program.set("albedo_map", unit);
    gl::ActiveTexture(GLenum(GL_TEXTURE0 + unit));
    gl::BindTexture(GL_TEXTURE_2D, textured ? textures_[size_t(g.albedo_map)].get() : 0);
}

void SceneMeshes::draw(size_t i) const {
    gl::BindVertexArray(objects_[i].vao.get());
    gl::DrawArrays(GL_TRIANGLES, 0, objects_[i].triangles * 3);
}

void SceneMeshes::draw_instanced(size_t i, int instances) const {
    gl::BindVertexArray(objects_[i].vao.get());
    gl::DrawArraysInstanced(GL_TRIANGLES, 0, objects_[i].triangles * 3, instances);
}

void SceneMeshes::draw_instanced(size_t i, int first, int count, int instances) const {
    gl::BindVertexArray(objects_[i].vao.get());
    gl::DrawArraysInstanced(GL_TRIANGLES, first * 3, count * 3, instances);
}

}  // namespace ag::gpu
