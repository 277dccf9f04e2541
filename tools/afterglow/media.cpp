// afterglow media SCENE -o OUT.exr: Pfeuti's method (2009) on the scene's media and glass: the
// volume term by voxelisation, curved photon marching and the view march on the GPU, with the
// time of each pass (docs/media.md).
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "gpu/gl_context.h"
#include "shared/image.h"
#include "shared/media_grid.h"
#include "shared/pipeline/media_method.h"
#include "shared/scene_file.h"
#include "tools/afterglow/commands.h"

namespace ag::cli {

const Command kMediaCommand{
    "media",
    "SCENE -o OUT.exr [options]",
    "Render the volume term of the scene's participating media by Pfeuti's method: voxel grids "
    "of n, sigma_s and sigma_t through the ray tracer, n smoothed by a 9^3 Gaussian, photons of "
    "the first point light's photon plane marched along curved paths on the GPU, single "
    "scattering by a view march. Writes OUT.exr and OUT.png, and OUT.specular.exr (what the camera "
    "sees through the glass: the view march on through it, bent, then the surface behind), "
    "OUT.indirect.exr (the light the fog scatters onto the surfaces the camera sees, the frame's "
    "indirect term's media part, before the camera ray's transmittance), OUT.transmittance.exr "
    "(the camera ray's transmittance up to the first surface), and prints the time of each pass.",
    {
        text("output,o", "OUT.exr", "the volume term"),
        integer("grid", "N", "voxels along the grid's longest side", 4, 512,
                MediaMethodSettings{}.grid),
        integer("photons", "N", "photons on the photon plane", 1, 1 << 26,
                MediaMethodSettings{}.photons),
        choice("deposit", "MODE", "photon deposits:", {"track", "walk"}, "track"),
        number("step", "VOXELS", "photon march step", 0.01, 4.0, MediaMethodSettings{}.march_step),
        flag("no-octree",
             "march photons in fixed steps everywhere (default: his octree, whole runs of steps "
             "at once through cubes of constant index and extinction; the same result)"),
        flag("his-phase",
             "the view march's phase at each voxel's mean photon direction alone, as his (default: "
             "broadened by the spread of the photons' directions there)"),
        integer("surface-bounces", "N",
                "photons leaving the grid go on from the opaque surface they meet (mirror: "
                "reflected; else cosine, times the grey albedo) and are marched again, up to N "
                "times (0: light from the light only, as his)",
                0, 16, MediaMethodSettings{}.surface_bounces),
        integer("surface-rays", "N",
                "view-march rays per pixel over the hemisphere of the surface the camera sees, "
                "for the light the fog scatters onto it (0: none)",
                0, 4096, MediaMethodSettings{}.fog_on_surfaces_rays),
        integer("emissive-photons", "N",
                "photons from the scene's emissive surfaces (mesh lights and lamps that are no "
                "light): at least N, more where their power over the light's asks for more (0: "
                "none)",
                0, 1 << 26, MediaMethodSettings{}.emissive_photons),
        flag("adaptive",
             "his adaptive pipeline (ch. 3.2): pilot photons, importance-sampled photons "
             "(--photons of them), per-voxel mipmap filtering"),
        integer("pilots", "SIDE", "adaptive: pilot photons per side of the plane's grid", 2, 1024,
                MediaAdaptiveSettings{}.pilot_side),
        number("background", "X", "adaptive: density of unselected cells, relative to the peak",
               1e-4, 1.0, MediaAdaptiveSettings{}.background),
        number(
            "delta-weight", "W",
            "adaptive: photon weight per mipmap level, for a 64-voxel grid (scaled by 64 / --grid)",
            1e-12, 1.0, MediaAdaptiveSettings{}.delta_weight),
        number(
            "significance", "Z",
            "adaptive: a voxel climbs a mipmap level only while the step to it is within Z "
            "standard errors, each level's relative error 1/sqrt(photons crossing its voxel) (0: "
            "off, his filter)",
            0.0, 1e9, MediaAdaptiveSettings{}.significance),
        number("gradient", "X",
               "adaptive: a coarse voxel is sampled tightly where its fluence gradient times its "
               "size reaches X times the mean fluence",
               0.0, 1e6, MediaAdaptiveSettings{}.gradient),
        number("shadow", "X",
               "adaptive: ... or where its fluence is at most X times the mean (0: never)", 0.0,
               1.0, MediaAdaptiveSettings{}.shadow),
        flag("integer-level",
             "adaptive: his integer weight level floor(w / delta-weight) instead of the "
             "fractional w / delta-weight (blending the two mipmap levels around it)"),
        flag("constant-density",
             "adaptive: his piecewise-constant photon density over the plane's cells instead of "
             "the density read bilinearly between their centres"),
        flag("no-filter",
             "adaptive: the importance-sampled deposits as they are (no mipmap levels)"),
        number("dense-cut", "X",
               "adaptive, a light inside the grid: cells whose density exceeds the floor by more "
               "than X of the peak's excess form the dense set",
               0.0, 1.0, MediaAdaptiveSettings{}.dense_cut),
        integer("seed", "N",
                "adaptive: the pilots' jitter and the rotation of the importance-sampled "
                "Hammersley points; also the surface bounces' directions",
                0, 0x7fffffff, 0),
        flag("his-sphere",
             "adaptive, a light inside the grid: his pipeline (thresholds and filter on the "
             "fluence itself, one set of photons through the smooth density) instead of ours"),
        size_option("image size (default: the scene camera's resolution)"),
        flag(
            "slices",
            "also write OUT.{n,sigma_s,fluence}.exr: x-y slices through the grid centre (adaptive: "
            "OUT.level.exr and the photon density OUT.density.exr)"),
        number("exposure", "STOPS", "PNG exposure", -20.0, 20.0, 0.0),
        gl_option({gpu::GlBackend::osmesa, gpu::GlBackend::egl, gpu::GlBackend::automatic},
                  gpu::GlBackend::osmesa),
    },
    1,
    1,
};

int run_media(const Args& args) {
    const std::string where = "afterglow media";
    if (!args.has("output")) throw CliError(where + ": missing -o OUT.exr");
    const std::string out = args.get("output");
    if (std::filesystem::path(out).extension() != ".exr")
        throw CliError(where + ": -o expects a file name ending in .exr, got '" + out + "'");
    Scene scene = load_scene(args.positionals()[0]);
    args.get_size("size", scene.camera.width, scene.camera.height);
    MediaMethodSettings settings;
    settings.grid = args.get_int("grid");
    settings.photons = args.get_int("photons");
    settings.march_step = float(args.get_double("step"));
    settings.surface_bounces = args.get_int("surface-bounces");
    settings.fog_on_surfaces_rays = args.get_int("surface-rays");
    settings.emissive_photons = args.get_int("emissive-photons");
    settings.octree = !args.has("no-octree");
    settings.phase_spread = !args.has("his-phase");
    settings.deposit = args.get("deposit") == "walk" ? gpu::MediaDeposit::voxel_walk
                                                     : gpu::MediaDeposit::track_length;
    settings.adaptive.enabled = args.has("adaptive");
    settings.adaptive.pilot_side = args.get_int("pilots");
    settings.adaptive.background = float(args.get_double("background"));
    settings.adaptive.delta_weight = float(args.get_double("delta-weight"));
    settings.adaptive.significance = float(args.get_double("significance"));
    settings.adaptive.gradient = float(args.get_double("gradient"));
    settings.adaptive.shadow = float(args.get_double("shadow"));
    settings.adaptive.reconstruct = !args.has("no-filter");
    settings.adaptive.fractional_level = !args.has("integer-level");
    settings.adaptive.bilinear_density = !args.has("constant-density");
    settings.adaptive.free_space = !args.has("his-sphere");
    settings.adaptive.stratified = !args.has("his-sphere");
    settings.adaptive.dense_cut = float(args.get_double("dense-cut"));
    settings.seed = uint32_t(args.get_int("seed"));
    settings.adaptive.seed = settings.seed;
    auto context = gpu::make_gl_context(args.gl_backend());
    // A scene without media or a point light is bad input: exit 1 with its message.
    const MediaMethodResult result = render_media(scene, settings);
    std::filesystem::create_directories(std::filesystem::absolute(out).parent_path());
    write_image(result.volume, out);
    const std::string png = out.substr(0, out.size() - 4) + ".png";
    write_image(result.volume, png, float(args.get_double("exposure")));
    // What the camera sees through the glass (the specular term at glass pixels), where any.
    if (!result.specular.pixels.empty())
        write_image(result.specular, out.substr(0, out.size() - 4) + ".specular.exr");
    // The light the fog scatters onto the surfaces the camera sees.
    if (!result.indirect.pixels.empty())
        write_image(result.indirect, out.substr(0, out.size() - 4) + ".indirect.exr");
    // The camera ray's transmittance up to the first surface (what dims the frame's other terms).
    if (!result.transmittance.pixels.empty())
        write_image(result.transmittance, out.substr(0, out.size() - 4) + ".transmittance.exr");
    if (args.has("slices")) {
        const int layer = result.grids.size.z / 2;
        const std::string stem = out.substr(0, out.size() - 4);
        write_image(grid_slice(result.grids, result.grids.n, 2, layer), stem + ".n.exr");
        write_image(grid_slice(result.grids, result.grids.sigma_s, 2, layer),
                    stem + ".sigma_s.exr");
        write_image(grid_slice(result.grids, result.fluence, 2, layer), stem + ".fluence.exr");
    }
    const MediaMethodTiming& t = result.timing;
    if (settings.adaptive.enabled)
        std::printf(
            "media: adaptive, %zu pilots marched; pilot generation %.1f ms, pilot marching %.1f "
            "ms, distribution %.1f ms, reconstruction %.1f ms\n",
            result.pilots_marched, 1e3 * t.pilot_generation, 1e3 * t.pilot_marching,
            1e3 * t.distribution, 1e3 * t.reconstruction);
    std::printf(
        "media: grid %dx%dx%d, %zu photons marched (+%zu from surfaces, +%zu from emissive "
        "surfaces), %dx%d pixels on %s\n"
        "  voxelisation %.1f ms, smoothing %.1f ms, octree %.1f ms, photon generation %.1f ms, "
        "photon marching %.1f ms, viewing %.1f ms, total %.1f ms\n",
        result.grid.x, result.grid.y, result.grid.z, result.photons_marched, result.photons_bounced,
        result.photons_emissive, scene.camera.width, scene.camera.height,
        context->renderer().c_str(), 1e3 * t.voxelisation, 1e3 * t.smoothing, 1e3 * t.octree,
        1e3 * t.photon_generation, 1e3 * t.photon_marching, 1e3 * t.viewing, 1e3 * t.total());
    if (!result.levels.empty() && args.has("slices")) {
        std::vector<float> levels(result.levels.begin(), result.levels.end());
        write_image(grid_slice(result.grids, levels, 2, result.grids.size.z / 2),
                    out.substr(0, out.size() - 4) + ".level.exr");
        // The photon density over the plane (or the sphere of directions), SIDE x SIDE.
        const int side = settings.adaptive.pilot_side;
        Image density(side, side);
        for (int y = 0; y < side; ++y)
            for (int x = 0; x < side; ++x)
                density.set_rgb(x, y, glm::vec3(float(result.density[size_t(y * side + x)])));
        write_image(density, out.substr(0, out.size() - 4) + ".density.exr");
    }
    std::cerr << where << ": wrote " << out << " and " << png << "\n";
    return 0;
}

static const Registration kRegistration(kMediaCommand, run_media, 52);

}  // namespace ag::cli
