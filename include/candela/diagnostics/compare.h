#pragma once
// `candela compare IMAGE REFERENCE`: the error of one image against another in linear radiance
// (docs/convergence.md "Comparing one image"): the measures of `candela converge` (MSE, relMSE,
// diagnostics/converge.h) and PSNR over the whole image and per cell of the stats block's region
// grid (render/region_grid.h), the pixels that contribute most, a false-colour error map, and,
// given candela's own layers of the image's scene by light-path order, which order is off and by
// how much.
#include "candela/diagnostics/converge.h"
#include "candela/render/film.h"
#include "candela/render/output.h"
#include "candela/render/region_grid.h"
#include "candela/render/settings.h"
#include "candela/scene/scene.h"

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace candela {

/// How the look an 8-bit image was decoded by was chosen.
enum class LookSource {
    None,     ///< a float image: no look
    Given,    ///< by the caller (compare --look)
    Recorded, ///< from the file's own metadata (exr::kLook, written by candela)
    Assumed,  ///< neither: kAssumedLook
};
/// The look of an 8-bit image that names none: most such images are the course renderer's.
constexpr Look kAssumedLook = Look::Cs184;

/// An image as linear radiance (Rec. 709 RGB), row 0 at the top, with the pixels that can be
/// compared: an 8-bit pixel with a channel at 255 is clipped (its value is unknown, only that
/// it is at least the curve's white), and a non-finite value has no meaning.
struct LinearImage {
    int width = 0, height = 0;
    std::vector<float> rgb;           ///< width * height * 3
    std::vector<std::uint8_t> usable; ///< width * height: 1 = compared, 0 = left out
    std::string decoding;             ///< how the file's values became linear radiance
    /// The linear value at which the file's 8-bit curve saturates (1/sqrt(2) for the CS184
    /// look, 1 for candela's); +inf for float images.
    double clip = std::numeric_limits<double>::infinity();
    /// Values up to this are black in the file (the 8-bit curve's byte 0 holds them all); 0 for
    /// float images.
    double black = 0.0;
    Look look = kAssumedLook;                  ///< 8-bit images: the look decoded by
    LookSource look_source = LookSource::None; ///< and how it was chosen
    /// What the reader should know about the decoding: a look given against the recorded one,
    /// a recorded exposure or tone map that the decoding does not undo.
    std::vector<std::string> warnings;
    /// Per pixel: 1 when the 8-bit file clips it (a channel at 255, stored as `clip`: what
    /// the file says is that the value is at least its white); such pixels are unusable for
    /// the error against a reference but enter the layer fit. Empty for float images.
    std::vector<std::uint8_t> clipped;
    std::size_t clipped_count = 0;
    /// The samples per pixel the image was rendered with (0: not known), which sets how much
    /// of its light the white clips (add_clipping_loss).
    int spp = 0;
    /// Per pixel channel (empty when not estimated): the expected light the white clips,
    /// E[X_N] - E[min(X_N, clip)] for X_N an N-sample estimate of the pixel, which the layer
    /// fit adds back to the image's value.
    std::vector<float> clip_loss;
    bool fitted(int x, int y) const {
        return ok(x, y) || (!clipped.empty() &&
                            clipped[std::size_t(y) * std::size_t(width) + std::size_t(x)] != 0);
    }
    float at(int x, int y, int c) const {
        return rgb[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3 + std::size_t(c)];
    }
    bool ok(int x, int y) const {
        return usable[std::size_t(y) * std::size_t(width) + std::size_t(x)] != 0;
    }
    Rgb pixel(int x, int y) const { return Rgb(at(x, y, 0), at(x, y, 1), at(x, y, 2)); }
};

/// The film's mean radiance (what its EXR stores), every pixel usable.
LinearImage linear_image(const Film& film);

/// An image file as linear radiance: EXR and other float formats as stored (R, G, B); 8-bit
/// files through the inverse of a look's curve (cs184_decode8 or srgb_decode8, output.h), with
/// clipped pixels left out of `usable` and marked in `clipped`. The look is `look` when given,
/// else the one the file records (candela's images do, exr::kLook), else kAssumedLook. `spp` is
/// the image's recorded candela:spp when it records --adaptive none (candela:adaptive), else 0.
/// Throws Error(Io) when the file cannot be read, has no R, G and B channels, or holds
/// 8-bit-format values that are not whole bytes (a 16-bit PNG).
LinearImage read_linear_image(const std::string& path, std::optional<Look> look);

/// PSNR's peak: radiance 1, the white of candela's own 8-bit look at 0 EV (the measure is
/// 10 log10(peak^2 / MSE) in linear radiance, so it is comparable across images of one scene).
constexpr double kPsnrPeak = 1.0;
/// PSNR in dB of an MSE (+inf for 0).
double psnr_of(double mse);

/// One pixel's error: its value, the reference's, its squared error summed over the channels
/// and that sum's share of the whole image's.
struct PixelError {
    int x = 0, y = 0;
    Rgb value, reference;
    double se = 0.0;
    double share = 0.0;
};

struct CompareResult {
    ImageError whole;
    double psnr = 0.0;
    RegionGrid grid;
    std::vector<ImageError> cells;  ///< per grid cell (the grid's order)
    std::vector<double> cell_share; ///< per cell: its share of the whole squared error
    /// Per cell: every compared value of both images is black in the coarser of the two files
    /// (LinearImage::black), so its error is only the decoding's.
    std::vector<std::uint8_t> cell_black;
    std::vector<PixelError> top; ///< the largest squared errors, largest first
    std::size_t compared = 0;    ///< pixels compared
    std::size_t left_out = 0;    ///< pixels unusable in either image
};

/// Compares `image` with `ref` (same size; Error(Usage) otherwise) over the pixels usable in
/// both, summing channels in the order image_error() does (so two films' EXRs give its figures
/// exactly), and keeps the `top_n` pixels with the largest squared error.
CompareResult compare_images(const LinearImage& image, const LinearImage& ref, int top_n);

/// The error map's scale: a pixel's relMSE (the mean over its channels of
/// (x - r)^2 / (r^2 + kRelMseEps)) on a log scale from 10^kErrorMapLogMin (blue) through
/// 10^-2 (green) to 10^kErrorMapLogMax (red), through the sample-rate ramp (output.h); 0 is
/// blue, pixels left out are black. A relMSE of 1e-4 is a relative RMS error of 1 %, 1 is 100 %.
constexpr double kErrorMapLogMin = -4.0;
constexpr double kErrorMapLogMax = 0.0;
/// The map is enlarged by a whole factor (each pixel a k x k block) to at least this width, so
/// that the legend's labels fit under it.
constexpr int kErrorMapMinWidth = 256;
/// Rows of the legend strip under the map.
constexpr int kErrorMapLegendRows = 28;

/// The colour of a pixel relMSE on the map's scale.
Rgb error_map_color(double rel_mse);

struct Image8 {
    int width = 0, height = 0;
    std::vector<unsigned char> rgb; ///< width * height * 3, row 0 at the top
};
/// The false-colour map of `image` against `ref` (same size), enlarged to kErrorMapMinWidth,
/// with the legend strip below it: the colour bar from 1E-4 to 1 with a tick and a label at
/// every decade.
Image8 error_map(const LinearImage& image, const LinearImage& ref);

/// The course's view: its `-r W H` image is the centre W x H of this view at the view's pixel
/// pitch (the batch-mode window of spec section 3.2), where candela's spans the whole view.
constexpr int kCourseViewWidth = 800, kCourseViewHeight = 600;

/// How an image lines up with a reference of the same scene: the correlation of their
/// structure (luminance capped at the 8-bit white and compressed by log(1 + L / mean)) as they
/// are and under the best of a set of reframings: shifts of up to kRegistrationMaxShift pixels,
/// zooms about the centre by kRegistrationZoomStep^k up to kRegistrationZoomSteps steps either
/// way, and the course's framing (zoom kCourseViewWidth / W) and its inverse.
struct Registration {
    double zoom = 1.0;         ///< the best reframing: image offsets from the centre = zoom x
                               ///< the reference's
    double dx = 0.0, dy = 0.0; ///< and its shift, reference pixels
    double identity = 0.0;     ///< structure correlation as the images are
    double best = 0.0;         ///< under the best reframing (identity when none is better)
    bool misregistered = false;
};
/// Shifts tried, pixels each way: a camera or pixel-centre convention off by a few pixels.
constexpr int kRegistrationMaxShift = 3;
/// Zooms tried: 1.04^k for k up to 30 either way, 0.31x to 3.2x in steps of 4 %.
constexpr double kRegistrationZoomStep = 1.04;
constexpr int kRegistrationZoomSteps = 30;
/// A reframing must see at least this share of the image inside the reference.
constexpr double kMinRegistrationOverlap = 0.25;
/// Misregistered: a reframing leaves at most this share of the unexplained structure variance
/// (1 - correlation^2) of the images as they are. Noise and a wrong order's light leave the
/// structure where it is, so they make every reframing worse than none; halving what is left
/// unexplained takes structure that lies elsewhere.
constexpr double kRegistrationGain = 0.5;
/// ... and correlates at least this well: structure found, not noise matched.
constexpr double kMinRegistrationCorrelation = 0.5;
/// A found zoom is the course's framing when within this of kCourseViewWidth / W (the zoom
/// grid's half step is 2 %; the course zoom itself is also tried).
constexpr double kCourseZoomTolerance = 0.021;

/// Checks how `image` lines up with `ref` (same size; Error(Usage) otherwise).
Registration check_registration(const LinearImage& image, const LinearImage& ref);
/// A misregistration as a verdict line: what the reframing is and the fix.
std::string describe_registration(const Registration& r, int width, int height);

/// How candela's layers of an image's light are cut.
enum class LayerSplit {
    Orders,        ///< one layer per scattering order k (-o 0 -m k)
    DirectIndirect ///< --light-paths direct and indirect
};
inline constexpr EnumTable<LayerSplit, 2> kLayerSplits = {{
    {LayerSplit::Orders, "orders", "one layer per light-path order, -o 0 -m k"},
    {LayerSplit::DirectIndirect, "direct-indirect", "--light-paths direct and indirect"},
}};

/// One layer to render: its name and the settings that make it.
struct LayerSpec {
    std::string name;
    RenderSettings settings;
    int order = -1; ///< its light-path order with LayerSplit::Orders, else -1
};

/// The name of light-path order k: emitters seen directly, direct light, one-bounce indirect,
/// two-bounce indirect, ...
std::string order_name(int k);

/// The layers whose sum has the expectation of a render with `image` settings (its -m, -o and
/// --light-paths): per order k <= m (only order m with -o 0), or direct and indirect. Each
/// layer renders `image.spp` uniform samples with the variance channel and a seed of its own,
/// far from the seeds renders use by default, so the layers are independent of each other and
/// of the image.
std::vector<LayerSpec> layer_specs(const RenderSettings& image, LayerSplit split);

/// A rendered layer.
struct Layer {
    std::string name;
    Film film;      ///< all its samples: the two halves merged
    int order = -1; ///< LayerSpec::order
    /// Two independent renders of it, of half the samples each (seeds of their own): the fit
    /// takes one as the other's instrument, so that no noise variance enters its estimate.
    Film half_a, half_b;
};
/// Renders each layer of `specs` on `scene` through the normal render API, as two halves of
/// its samples (each spec's spp must be at least 2).
std::vector<Layer> render_layers(const Scene& scene, const std::vector<LayerSpec>& specs);

/// candela's render as the sum of its layers' means (what compare uses without a REFERENCE).
LinearImage sum_of_layers(const std::vector<Layer>& layers);
/// Independent renders of the image's light the clipping loss is estimated from: enough for
/// kClipLossSamples samples per pixel in all, and at least kClipLossMinReplicas (so that the
/// loss's own spread across replicas is seen by the fit's residuals).
constexpr int kClipLossSamples = 256;
constexpr int kClipLossMinReplicas = 4;
/// Seeds of the clipping-loss replicas: far from renders' defaults, converge's and the layers'.
constexpr std::uint64_t kClipLossSeedBase = 0xc11b'0000'0000ull;
/// For an 8-bit image with clipped pixels and a known sample count N (image.spp): renders
/// max(kClipLossMinReplicas, kClipLossSamples / N) independent N-spp renders of `settings`
/// (the image's: its -m, -o, -l; its size) and sets image.clip_loss to the mean over them of
/// max(0, x - clip) per pixel channel: the light the file's white takes from an N-sample
/// image on average. Does nothing for an unknown N or when the fit has no clipped pixels
/// (fitted_clipped), so only 8-bit images with clipped pixels in the fit pay for the replicas.
void add_clipping_loss(LinearImage& image, const std::vector<Layer>& layers, const Scene& scene,
                       const RenderSettings& settings);
/// How many of the image's clipped pixels the layer fit uses (those not next to the white in
/// candela's layers, kFitClipMargin).
std::size_t fitted_clipped(const LinearImage& image, const std::vector<Layer>& layers);

/// Deviations of at least this many standard errors are named: for up to ~10 layers the chance
/// that noise alone names one is below 3 % (two-sided 0.27 % each).
constexpr double kLayerSignificanceZ = 3.0;
/// A layer is fitted only when its light's energy in the fitted pixels (sum mu^2, estimated by
/// the product of its two halves, sum L_a L_b) is at least this multiple of its noise's
/// (sum Var L). Below it the fit divides by an estimate about as uncertain as what it
/// divides, and the first-order standard error understates the spread (a ratio of noisy sums).
/// Other layers are reported as undetermined and enter the fit at scale 1.
constexpr double kMinLayerSignalToNoise = 10.0;

/// An 8-bit image's pixels next to one whose value in candela's layers (their sum, any channel)
/// reaches this fraction of the curve's white are left out of the fit as well as the clipped
/// ones: which pixels the image clips depends on its noise and on the very deviation measured,
/// so keeping only the unclipped ones near the white would bias the fit dark. A pixel at half
/// the white is clipped only by a deviation of 2x, beyond what the fit is for. The test reads
/// the 8 neighbours, not the pixel itself: a pixel chosen by its own layer noise would carry
/// layer values biased low (those that noise pushed over the line are gone), and the fit would
/// call the image bright.
constexpr double kFitClipMargin = 0.5;

/// An undetermined layer with less than this share of the light in the compared pixels is
/// said to have next to none there (an 8-bit image's clipped light panel), not to be noisy.
constexpr double kNoLightShare = 0.005;

/// An undetermined layer whose image has at least this cosine with another layer's is named as
/// indistinguishable from it: the two are nearly proportional (at 0.9 the part of one not along
/// the other is under 44 % of its size), so their scales trade off against each other.
constexpr double kLookAlikeCosine = 0.9;

/// The scale of one layer in the image (docs/convergence.md "Splitting the error by order").
struct LayerFit {
    std::string name;
    bool determined = false;  ///< false: too little of this layer's light in the compared pixels
    bool absent = false;      ///< a missing order (LayerAnalysis::first_missing), taken as 0
    double scale = 1.0;       ///< s_k; 1 = the image has exactly candela's light of this layer
    double std_err = 0.0;     ///< standard error of s_k
    double light_share = 0.0; ///< the layer's share of candela's light (sum over the pixels)
    /// Its light's energy in the fitted pixels over its noise's: sum mu^2 / sum Var L.
    double signal_to_noise = 0.0;
    bool significant = false; ///< |s_k - 1| > kLayerSignificanceZ std_err
    int main_cell = -1;       ///< grid cell holding most of (s_k - 1) L_k's squared size
    double main_cell_share = 0.0;
    /// The material (index into Scene::materials) first seen through the pixels that hold most
    /// of (s_k - 1) L_k's squared size, -1 when not known; and that share.
    int main_material = -1;
    double main_material_share = 0.0;
    /// An undetermined layer's look-alike: the other layer whose light over the fitted pixels
    /// is most nearly proportional to its own (the cosine of the two images), -1 when none.
    int like = -1;
    std::string like_name;
    double like_cosine = 0.0;
};

/// Per pixel, the material of the first surface the ray through the pixel's centre hits (lens
/// centre), -1 where it hits nothing: where in the scene a layer's deviation lies.
std::vector<int> first_hit_materials(const Scene& scene, const RenderSettings& settings);

/// Fits image ~ sum_k s_k layer_k by least squares over the pixel channels usable in `image`
/// (and, for an 8-bit image, not next to kFitClipMargin of its white in candela's layers),
/// with the layers' noise kept out of the normal equations by taking each layer's two halves
/// as each other's instruments (errors in variables), and a residual-based (sandwich)
/// standard error. Layers must match the image's size and carry the variance channel.
/// `materials` (first_hit_materials(), or empty) lets each fit name its main material.
std::vector<LayerFit> fit_layers(const LinearImage& image, const std::vector<Layer>& layers,
                                 const RegionGrid& grid, const std::vector<int>& materials = {});

/// The fit as text, one line per layer, then a verdict naming the layers that are off, where in
/// the grid and (with `material_names`, Scene::materials' names) on which material.
std::string describe_layer_fit(const std::vector<LayerFit>& fits, const RegionGrid& grid,
                               const std::vector<std::string>& material_names = {});

/// The layer fit with the two readings that are not one order's error: orders missing from the
/// image, and one factor common to every order.
struct LayerAnalysis {
    /// Per layer; with missing orders, those are `absent` and the others fitted without them.
    std::vector<LayerFit> fits;
    /// The first order missing from the image (all from it on are), -1 when none: the smallest
    /// order k whose layers from k on, fitted as one scale, are within kLayerSignificanceZ
    /// standard errors of 0 and beyond them from 1 (an image rendered with -m k-1).
    int first_missing = -1;
    LayerFit missing;             ///< that tail's one fitted scale
    LayerFit common;              ///< the present layers fitted as one scale
    bool common_explains = false; ///< every determined order within kLayerSignificanceZ
                                  ///< combined standard errors of `common`'s scale
    /// Clipped pixels in the fit with no clipping loss added back (the image's samples per
    /// pixel unknown): the fit may read the image dark.
    std::size_t clipped_unknown_spp = 0;
};

/// fit_layers() and the two readings above (missing orders only when every layer is an order).
LayerAnalysis analyse_layers(const LinearImage& image, const std::vector<Layer>& layers,
                             const RegionGrid& grid, const std::vector<int>& materials = {});

/// The analysis as text: describe_layer_fit()'s lines, then one verdict: the missing orders
/// (and any present order that is off), or the whole image's common factor when every order
/// agrees with it and it is off, or the orders that are off, or that every layer matches.
std::string describe_layer_analysis(const LayerAnalysis& analysis, const RegionGrid& grid,
                                    const std::vector<std::string>& material_names = {});

} // namespace candela
