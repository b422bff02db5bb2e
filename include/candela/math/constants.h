#pragma once
// Mathematical constants and angle conversions, in float (render code) and double (scene
// loading, reports).
namespace candela {

constexpr double kPiD = 3.14159265358979323846;
constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 1.f / kPi;
constexpr float kInv2Pi = 1.f / (2.f * kPi);
constexpr float kInv4Pi = 1.f / (4.f * kPi);

/// Radians per degree.
constexpr float kDegToRad = kPi / 180.f;
constexpr double kDegToRadD = kPiD / 180.0;

/// `deg` degrees in radians: one multiplication by the rounded constant pi / 180.
constexpr float deg_to_rad(float deg) {
    return deg * kDegToRad;
}
constexpr double deg_to_rad(double deg) {
    return deg * kDegToRadD;
}

/// `rad` radians in degrees: one division by the rounded constant pi / 180, so that
/// rad_to_deg(deg_to_rad(x)) stays within an ulp or two of x.
constexpr float rad_to_deg(float rad) {
    return rad / kDegToRad;
}
constexpr double rad_to_deg(double rad) {
    return rad / kDegToRadD;
}

} // namespace candela
