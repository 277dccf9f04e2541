#include "shared/camera.h"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

namespace ag {

glm::mat4 view_matrix(const Camera& camera) {
    return glm::lookAt(camera.eye, camera.target, camera.up);
}

glm::mat4 projection_matrix(const Camera& camera, float near_plane, float far_plane) {
    return glm::perspective(glm::radians(camera.fov_y), float(camera.width) / float(camera.height),
                            near_plane, far_plane);
}

glm::vec3 camera_ray_direction(const Camera& camera, float px, float py) {
    const glm::vec3 forward = glm::normalize(camera.target - camera.eye);
    const glm::vec3 right = glm::normalize(glm::cross(forward, camera.up));
    const glm::vec3 up = glm::cross(right, forward);
    const float tan_half = std::tan(glm::radians(camera.fov_y) * 0.5f);
    const float aspect = float(camera.width) / float(camera.height);
    const float sx = (2.0f * px / float(camera.width) - 1.0f) * tan_half * aspect;
    const float sy = (1.0f - 2.0f * py / float(camera.height)) * tan_half;
    return glm::normalize(forward + sx * right + sy * up);
}

float pixel_world_area(const Camera& camera, float distance, float cos_n) {
    // Eq. 12.2 with square pixels: the pixel's footprint at distance d, divided by n·e.
    const float tan_half = std::tan(glm::radians(camera.fov_y) * 0.5f);
    const float pixel = 2.0f * distance * tan_half / float(camera.height);
    return pixel * pixel / std::max(1e-6f, cos_n);
}

}  // namespace ag
