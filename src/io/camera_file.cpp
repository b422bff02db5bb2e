// The CS184 camera settings file of `render -c`: read, checked and applied to the scene camera.
#include "candela/io/camera_file.h"

#include "candela/scene/scene.h"
#include "candela/util/error.h"

#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>

namespace candela {

namespace {

/// How far from orthonormal the camera-to-world matrix of a camera file may be: the course GUI
/// writes six significant digits, whose rounding moves lengths and dot products by about 1e-5;
/// a matrix 100 times further off is not a rotation written out, and would shear the image.
constexpr double kAxisTolerance = 1e-3;

/// Refuses a camera-to-world matrix (numbers 16..24, row-major, columns = camera X, Y, Z) whose
/// columns are not unit length and pairwise orthogonal: an all-zero matrix renders black, a
/// sheared one a distorted image.
void check_camera_axes(const std::string& path, const std::vector<double>& v,
                       const std::vector<int>& lines) {
    constexpr std::size_t kFirst = 16; // after the lens/clip (5), pose (6) and orbit (5) numbers
    const double* m = &v[kFirst];
    const auto column = [m](int c) { return std::array<double, 3>{m[c], m[3 + c], m[6 + c]}; };
    const auto dot = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
        return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    };
    const char* names[3] = {"X", "Y", "Z"};
    std::string why;
    for (int c = 0; c < 3 && why.empty(); ++c) {
        const double len = std::sqrt(dot(column(c), column(c)));
        if (!(std::abs(len - 1.0) <= kAxisTolerance))
            why = std::string("the camera ") + names[c] + " axis (column " + std::to_string(c) +
                  " of the camera-to-world matrix) has length " + std::to_string(len) + ", not 1";
    }
    for (int a = 0; a < 3 && why.empty(); ++a)
        for (int b = a + 1; b < 3 && why.empty(); ++b)
            if (!(std::abs(dot(column(a), column(b))) <= kAxisTolerance))
                why = std::string("the camera ") + names[a] + " and " + names[b] +
                      " axes (columns of the camera-to-world matrix) are not perpendicular";
    if (!why.empty())
        throw Error(ErrorKind::Scene, SourceLoc{path, lines[kFirst]},
                    why + "; the matrix must be a rotation");
}

} // namespace

CameraFile read_camera_file(const std::string& path) {
    const std::string why = file_read_failure(path);
    if (!why.empty())
        throw Error(ErrorKind::Io, SourceLoc{path}, "cannot open camera file: " + why);
    std::ifstream in(path);
    if (!in) throw Error(ErrorKind::Io, SourceLoc{path}, "cannot open camera file");
    CameraFile file;
    file.path = path;
    std::vector<double>& v = file.values;
    std::vector<int> lines; // the line of each number
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
            throw Error(ErrorKind::Scene, SourceLoc{path, line},
                        "'" + tok + "' is not a finite number");
        v.push_back(d);
        lines.push_back(line);
        i = j;
    }
    // hFov vFov aspect nClip fClip | pos(3) target(3) | phi theta r minR maxR | c2w(9) |
    // screenW screenH screenDist | focalDistance lensRadius  = 5+6+5+9+3+2 = 30 numbers.
    constexpr std::size_t kCameraFileNumbers = 30;
    if (v.size() != kCameraFileNumbers)
        throw Error(ErrorKind::Scene, SourceLoc{path, line},
                    "expected " + std::to_string(kCameraFileNumbers) +
                        " numbers in a camera settings file, found " + std::to_string(v.size()));
    const double hfov = v[0], znear = v[3], zfar = v[4];
    if (!(hfov > 0.0 && hfov < 180.0) || !(znear >= 0.0) || !(zfar > znear))
        throw Error(ErrorKind::Scene, SourceLoc{path},
                    "camera field of view or clip planes out "
                    "of range");
    check_camera_axes(path, v, lines);
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
