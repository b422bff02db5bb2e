#include "candela/io/camera_file.h"

#include "candela/scene/scene.h"
#include "candela/util/error.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>

namespace candela {

CameraFile read_camera_file(const std::string& path) {
    const std::string why = file_read_failure(path);
    if (!why.empty()) throw Error(ErrorKind::Io, path + ": error: cannot open camera file: " + why);
    std::ifstream in(path);
    if (!in) throw Error(ErrorKind::Io, path + ": error: cannot open camera file");
    CameraFile file;
    file.path = path;
    std::vector<double>& v = file.values;
    std::string tok;
    int line = 1;
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::size_t i = 0;
    while (i < text.size()) {
        while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) {
            if (text[i] == '\n') ++line;
            ++i;
        }
        std::size_t j = i;
        while (j < text.size() && !std::isspace(static_cast<unsigned char>(text[j])))
            ++j;
        if (j == i) break;
        tok = text.substr(i, j - i);
        char* end = nullptr;
        double d = std::strtod(tok.c_str(), &end);
        if (end != tok.c_str() + tok.size() || !std::isfinite(d))
            throw Error(ErrorKind::Scene, path + ":" + std::to_string(line) + ": error: '" + tok +
                                              "' is not a finite number");
        v.push_back(d);
        i = j;
    }
    // hFov vFov aspect nClip fClip | pos(3) target(3) | phi theta r minR maxR | c2w(9) |
    // screenW screenH screenDist | focalDistance lensRadius  = 5+6+5+9+3+2 = 30 numbers.
    constexpr std::size_t kCameraFileNumbers = 30;
    if (v.size() != kCameraFileNumbers)
        throw Error(ErrorKind::Scene, path + ":" + std::to_string(line) + ": error: expected " +
                                          std::to_string(kCameraFileNumbers) +
                                          " numbers in a camera settings file, found " +
                                          std::to_string(v.size()));
    const double hfov = v[0], znear = v[3], zfar = v[4];
    if (!(hfov > 0.0 && hfov < 180.0) || !(znear >= 0.0) || !(zfar > znear))
        throw Error(ErrorKind::Scene, path + ": error: camera field of view or clip planes out "
                                             "of range");
    return file;
}

void apply_camera_file(const CameraFile& file, Scene& scene) {
    const std::vector<double>& v = file.values;
    Camera& c = scene.camera;
    c.hfov_deg = float(v[0]);
    c.znear = float(v[3]);
    c.zfar = float(v[4]);
    c.pos = Vec3(float(v[5]), float(v[6]), float(v[7]));
    c.target = Vec3(float(v[8]), float(v[9]), float(v[10]));
    // c2w is row-major; its columns are the camera X, Y, Z axes.
    const double* m = &v[16];
    c.x = normalize(Vec3(float(m[0]), float(m[3]), float(m[6])));
    c.y = normalize(Vec3(float(m[1]), float(m[4]), float(m[7])));
    c.z = normalize(Vec3(float(m[2]), float(m[5]), float(m[8])));
    c.focal_distance = float(v[28]);
    c.lens_radius = float(v[29]);
}

void apply_camera_file(const std::string& path, Scene& scene) {
    apply_camera_file(read_camera_file(path), scene);
}

} // namespace candela
