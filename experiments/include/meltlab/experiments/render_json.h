#pragma once
// Cameras and render scenes as JSON, written at the edge (run records, manifests, truth files).
// nlohmann-json prints every double as the shortest decimal that reads back to the same value,
// so a camera written here and read back with render::parse_camera is the same camera, bit for
// bit (the observation manifests rely on it).
#include <meltlab/render/camera.h>
#include <meltlab/render/render_scene.h>

#include <nlohmann/json.hpp>

namespace meltlab::experiments {

/// {"type": "orthographic", width, height, pixels_per_unit, centre} or {"type": "pinhole",
/// width, height, fx, fy, cx, cy, distortion, camera_from_world (4 x 4 rows)}: the keys
/// render::parse_camera reads.
nlohmann::json camera_json(const render::Camera& camera);

/// Everything a render used: camera ("auto" when fitted to the mesh), texture filter, lights,
/// ice and ground materials with their texture sources, environment, outputs.
nlohmann::json render_scene_json(const render::RenderScene& scene);

}  // namespace meltlab::experiments
