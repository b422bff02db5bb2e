#pragma once
// The CS184 camera settings file read by `render -c` (spec §8.2): 30 whitespace-separated
// numbers in the course's layout, checked when read.
#include <string>
#include <vector>

namespace candela {

class Scene;

/// A CS184 camera settings file (spec §8.2): the 30 numbers, checked.
struct CameraFile {
    std::string path;
    std::vector<double> values;
};

/// Reads and checks a CS184 camera settings file (spec §8.2). Throws Error(Io) when it cannot
/// be opened, Error(Scene) with file:line when it is malformed.
CameraFile read_camera_file(const std::string& path);

/// Applies a CS184 camera settings file to the scene camera.
void apply_camera_file(const CameraFile& file, Scene& scene);
/// read_camera_file + apply_camera_file.
void apply_camera_file(const std::string& path, Scene& scene);

} // namespace candela
