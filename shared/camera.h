// The camera model shared by the GL frame and the CPU reference renderers, so both see the same
// pixels: a pinhole at `eye` looking at `target`, vertical FOV in degrees, square pixels. Pixel
// (x, y) has its top-left corner at (x, y); row 0 is the top of the image.
#pragma once

#include <glm/glm.hpp>

#include "shared/scene.h"

namespace ag {

glm::mat4 view_matrix(const Camera& camera);  // world -> eye (GL, looks down −z)
glm::mat4 projection_matrix(const Camera& camera, float near_plane,
                            float far_plane);  // GL clip space

// World-space ray through image position (px, py) in pixels (px + 0.5 is a pixel centre).
// Returns the unit direction; the origin is camera.eye.
glm::vec3 camera_ray_direction(const Camera& camera, float px, float py);

// World area one pixel covers on a surface at distance `distance` with cosine `cos_n` between its
// normal and the view direction (Larsen eq. 12.2 uses this to keep caustics' brightness).
float pixel_world_area(const Camera& camera, float distance, float cos_n);

}  // namespace ag
