// `candela compare IMAGE [REFERENCE]`: the error of one image against another in linear
// radiance, and with --scene, which light-path order of the image is off (diagnostics/compare.h).
#include "commands.h"
#include "output_paths.h"

#include "candela/app/cli.h"
#include "candela/diagnostics/compare.h"
#include "candela/io/collada.h"
#include "candela/io/image_io.h"
#include "candela/render/exr_layout.h"
#include "candela/scene/builder.h"
#include "candela/util/error.h"
#include "candela/util/log.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace candela::app {

namespace {

struct CompareArgs {
    std::string image, reference;
    std::string look = enum_name(kLooks, kAssumedLook);
    bool look_given = false; ///< --look given: it overrides the looks images record
    std::string error_map;
    int top = 10;
    std::string scene;
    std::string split = enum_name(kLayerSplits, LayerSplit::Orders);
    std::vector<int> resolution;
    std::string framing = enum_name(kFramings, Framing::Candela);
    int max_depth = RenderSettings{}.max_depth;
    int accumulate = 1;
    int light_samples = 1;
    int spp = 64;
    int image_spp = 0;
    bool image_spp_given = false;
    int threads = 0;
    LogArgs log;
};

/// The settings the image was made with (what the layers must add up to), checked before any
/// file is read.
RenderSettings image_settings(const CompareArgs& a) {
    RenderSettings s;
    if (a.max_depth < 0) throw Error(ErrorKind::Usage, "-m/--max-depth must be >= 0");
    if (a.accumulate != 0 && a.accumulate != 1)
        throw Error(ErrorKind::Usage,
                    "-o/--accumulate: " + std::to_string(a.accumulate) + " is not 0 or 1");
    if (a.light_samples < 1) throw Error(ErrorKind::Usage, "-l/--light-samples must be >= 1");
    // Each layer is two independent halves of its samples (diagnostics/compare.h, Layer).
    if (a.spp < 2) throw Error(ErrorKind::Usage, "-s/--spp must be >= 2");
    if (!a.resolution.empty() &&
        (a.resolution.size() != 2 || a.resolution[0] < 1 || a.resolution[1] < 1))
        throw Error(ErrorKind::Usage, "-r/--resolution needs two sizes >= 1");
    s.max_depth = a.max_depth;
    s.accumulate = a.accumulate == 1;
    s.light_samples = a.light_samples;
    s.spp = a.spp;
    s.threads = a.threads;
    return s;
}

/// The grid's values, "black" in the cells black in both images.
std::string grid_text(const RegionGrid& grid, const std::vector<double>& values,
                      const char* cell_format, const std::vector<std::uint8_t>& black) {
    std::string out;
    for (int r = 0; r < grid.rows; ++r) {
        out += "               ";
        for (int c = 0; c < grid.cols; ++c) {
            const std::size_t i = std::size_t(r * grid.cols + c);
            out += black[i] ? std::string("     black")
                            : fmt::format(fmt::runtime(cell_format), values[i]);
        }
        out += "\n";
    }
    return out;
}

/// The warnings of the images' decoding, and one for the 8-bit images whose look was assumed:
/// which look, and how to name another.
void warn_about_looks(const std::vector<std::pair<std::string, const LinearImage*>>& images) {
    std::vector<std::string> assumed;
    for (const auto& [path, img] : images) {
        for (const std::string& w : img->warnings)
            print_warning(w, "compare");
        if (img->look_source == LookSource::Assumed) assumed.push_back(path);
    }
    if (assumed.empty()) return;
    std::string names;
    for (const std::string& p : assumed)
        names += (names.empty() ? "" : " and ") + p;
    const char* was = assumed.size() == 1 ? "it was" : "they were";
    print_warning(fmt::format("{} {} no record of the look {} written in; decoded in look {} (the "
                              "course's curve); if {} written in candela's look, give --look "
                              "candela",
                              names, assumed.size() == 1 ? "has" : "have", was,
                              enum_name(kLooks, kAssumedLook), was),
                  "compare");
}

int run_compare(const CompareArgs& a) {
    set_log_level(log_level_of(a.log));
    std::optional<Look> look;
    if (a.look_given) look = parse_enum(kLooks, "--look", a.look);
    const LayerSplit split = parse_enum(kLayerSplits, "--split", a.split);
    const Framing framing = parse_enum(kFramings, "--framing", a.framing);
    if (a.top < 0) throw Error(ErrorKind::Usage, "--top must be >= 0");
    if (a.reference.empty() && a.scene.empty())
        throw Error(ErrorKind::Usage,
                    "give a REFERENCE image, or --scene to compare with candela's render");
    RenderSettings settings = image_settings(a);
    check_distinct_files({{"the image being compared", a.image},
                          {"the reference image", a.reference},
                          {"--scene", a.scene}},
                         {{"--error-map", a.error_map}});
    if (!a.error_map.empty()) {
        if (output_kind(a.error_map) != OutputKind::Ldr)
            throw Error(ErrorKind::Usage,
                        "--error-map: '" + a.error_map + "' is not an 8-bit image name (use .png)");
        check_image_writable(a.error_map, OutputKind::Ldr);
    }
    if (!a.scene.empty()) check_scene_file(a.scene);

    if (a.image_spp_given && a.image_spp < 1)
        throw Error(ErrorKind::Usage,
                    "--image-spp must be >= 1 (got " + std::to_string(a.image_spp) + ")");
    LinearImage image = read_linear_image(a.image, look);
    if (a.image_spp > 0) image.spp = a.image_spp;
    std::vector<Layer> layers;
    std::vector<int> materials;              // first hit per pixel (with --scene)
    std::vector<std::string> material_names; // Scene::materials' names (with --scene)
    if (!a.scene.empty()) {
        if (!a.resolution.empty() &&
            (a.resolution[0] != image.width || a.resolution[1] != image.height))
            throw Error(ErrorKind::Usage,
                        "-r/--resolution " + std::to_string(a.resolution[0]) + " " +
                            std::to_string(a.resolution[1]) + " differs from " + a.image + "'s " +
                            std::to_string(image.width) + "x" + std::to_string(image.height));
        settings.width = image.width;
        settings.height = image.height;
        Diagnostics diag(false);
        BuildOptions build;
        build.framing = framing;
        Scene scene = load_scene(a.scene, build, diag);
        diag.flush();
        frame_camera(scene.camera, build.framing, image.width);
        const std::vector<LayerSpec> specs = layer_specs(settings, split);
        if (log_level() >= LogLevel::Info)
            fmt::print(stderr, "compare: rendering {} layers of {}, {}x{}, {} spp each\n",
                       specs.size(), a.scene, image.width, image.height, settings.spp);
        layers = render_layers(scene, specs);
        // Only an 8-bit image with clipped pixels in the fit and a known sample count pays
        // for the clipping loss's replicas.
        if (image.spp > 0 && fitted_clipped(image, layers) > 0 && log_level() >= LogLevel::Info)
            fmt::print(stderr, "compare: estimating the light the white clips at {} spp\n",
                       image.spp);
        add_clipping_loss(image, layers, scene, settings);
        materials = first_hit_materials(scene, settings);
        for (const Material& m : scene.materials)
            material_names.push_back(m.name);
    }
    LinearImage ref;
    if (!a.reference.empty()) {
        ref = read_linear_image(a.reference, look);
    } else {
        ref = sum_of_layers(layers);
    }
    warn_about_looks({{a.image, &image}, {a.reference, &ref}});

    const CompareResult r = compare_images(image, ref, a.top);
    std::string out = fmt::format("compare {} against {}, {}x{}, in linear radiance\n", a.image,
                                  a.reference.empty() ? "candela's render" : a.reference,
                                  image.width, image.height);
    out += "  image        " + image.decoding + "\n";
    out += "  reference    " + ref.decoding + "\n";
    out += fmt::format("  compared     {} of {} pixels\n", r.compared, r.compared + r.left_out);
    out += fmt::format("whole image    MSE {:.4g}  relMSE {:.4g}  PSNR {:.2f} dB (peak radiance "
                       "{:g})\n",
                       r.whole.mse, r.whole.rel_mse, r.psnr, kPsnrPeak);
    std::vector<double> rel, share;
    for (std::size_t i = 0; i < r.cells.size(); ++i) {
        rel.push_back(r.cells[i].rel_mse);
        share.push_back(100.0 * r.cell_share[i]);
    }
    out += "by region      relMSE, top row first:\n" +
           grid_text(r.grid, rel, "{:10.3g}", r.cell_black);
    out += "               share of the squared error (%):\n" +
           grid_text(r.grid, share, "{:10.1f}", r.cell_black);
    if (std::find(r.cell_black.begin(), r.cell_black.end(), 1) != r.cell_black.end())
        out += "               black: black in both images (no error beyond the decoding's)\n";
    if (!r.top.empty()) {
        out += "largest errors (x, y from the top-left: image RGB / reference RGB, share of the "
               "squared error):\n";
        for (std::size_t i = 0; i < r.top.size(); ++i) {
            const PixelError& p = r.top[i];
            out += fmt::format("  {:2}. ({}, {})  {:.4g} {:.4g} {:.4g} / {:.4g} {:.4g} {:.4g}  "
                               "{:.1f} %\n",
                               i + 1, p.x, p.y, p.value.x, p.value.y, p.value.z, p.reference.x,
                               p.reference.y, p.reference.z, 100.0 * p.share);
        }
    }
    const Registration reg = check_registration(image, ref);
    if (reg.misregistered) {
        out += describe_registration(reg, image.width, image.height);
    } else if (!layers.empty()) {
        out += fmt::format("by light-path layer (candela's, {} spp each; the image's scale of "
                           "each, fitted by least squares):\n",
                           settings.spp);
        out += describe_layer_analysis(analyse_layers(image, layers, r.grid, materials), r.grid,
                                       material_names);
    }
    if (!a.error_map.empty()) {
        const Image8 map = error_map(image, ref);
        write_image8(a.error_map, map.width, map.height, map.rgb,
                     {{exr::kSoftware, software_text()}, {exr::kCommandLine, command_line_text()}});
        out += fmt::format("error map      {}: pixel relMSE, log scale 1E{} (blue) to 1E{} "
                           "(green) to 1 (red); black: left out\n",
                           a.error_map, int(kErrorMapLogMin),
                           int((kErrorMapLogMin + kErrorMapLogMax) / 2));
    }
    std::fputs(out.c_str(), stdout);
    return 0;
}

} // namespace

void add_compare_command(CLI::App& app, int* status) {
    auto a = std::make_shared<CompareArgs>();
    CLI::App* cmd = app.add_subcommand(
        "compare",
        "The error of an image against a reference in linear radiance: MSE, relMSE and PSNR of "
        "the whole image and per region, the pixels that contribute most, a false-colour error "
        "map; with --scene, candela's layers by light-path order and which of them the image "
        "has wrong");
    cmd->add_option("image", a->image, "The image to judge: EXR, HDR or 8-bit (PNG, ...)")
        ->required();
    cmd->add_option("reference", a->reference,
                    "The reference image (default with --scene: candela's render, the sum of "
                    "its layers)");
    cmd->add_option("--look", a->look,
                    "How 8-bit images are decoded to linear radiance: " + enum_choices(kLooks) +
                        ". Default: the look a candela image records, else " +
                        enum_name(kLooks, kAssumedLook) + " (with a warning)");
    cmd->add_option("--error-map", a->error_map,
                    "Write the false-colour error map (pixel relMSE, log scale 1E-4 blue to 1 "
                    "red, legend below) to this PNG");
    cmd->add_option("--top", a->top, "How many of the largest pixel errors to list")
        ->capture_default_str();
    cmd->add_option("--scene", a->scene,
                    "The image's scene (.dae): render candela's layers of it by light-path order "
                    "and fit the image's scale of each");
    cmd->add_option("--split", a->split, "--scene: the layers: " + enum_choices(kLayerSplits))
        ->capture_default_str();
    cmd->add_option("-m,--max-depth", a->max_depth,
                    "--scene: the image's maximum scattering events")
        ->capture_default_str();
    cmd->add_option("-o,--accumulate", a->accumulate,
                    "--scene: the image's -o: 1 all orders up to -m, 0 only order -m")
        ->capture_default_str();
    cmd->add_option("-l,--light-samples", a->light_samples,
                    "--scene: light samples per vertex of the layers")
        ->capture_default_str();
    cmd->add_option("-r,--resolution", a->resolution,
                    "--scene: the image's width and height (checked against the image)")
        ->expected(2);
    cmd->add_option("--framing", a->framing,
                    "--scene: the image's framing, as render --framing: " +
                        enum_choices(kFramings, {", ", " or ", "", "", false}))
        ->capture_default_str();
    cmd->add_option("-s,--spp", a->spp, "--scene: samples per pixel of each layer")
        ->capture_default_str();
    cmd->add_option("--image-spp", a->image_spp,
                    "--scene: the samples per pixel the 8-bit image was rendered with, for the "
                    "light its white clips (default: what the file records, if anything)");
    cmd->add_option("-t,--threads", a->threads, "Worker threads; 0 = all cores")
        ->capture_default_str();
    add_log_options(*cmd, a->log);
    cmd->callback([a, status, cmd] {
        a->look_given = cmd->count("--look") > 0;
        a->image_spp_given = cmd->count("--image-spp") > 0;
        // The layers' settings mean nothing without the scene they render.
        const std::pair<const char*, const char*> layer_flags[] = {
            {"--split", "--split"},
            {"--max-depth", "-m/--max-depth"},
            {"--accumulate", "-o/--accumulate"},
            {"--light-samples", "-l/--light-samples"},
            {"--resolution", "-r/--resolution"},
            {"--framing", "--framing"},
            {"--spp", "-s/--spp"},
            {"--image-spp", "--image-spp"}};
        if (a->scene.empty())
            for (const auto& [flag, name] : layer_flags)
                if (cmd->count(flag) > 0)
                    throw Error(ErrorKind::Usage, std::string(name) +
                                                      " describes the layers of --scene; give "
                                                      "--scene SCENE.dae with it");
        *status = run_compare(*a);
    });
}

} // namespace candela::app
