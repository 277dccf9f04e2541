// Checks on what `afterglow view` wrote in the viewer tests (viewer_test.sh): screenshots are not
// blank, a region changed between two screenshots, and the --dump JSON shows a dragged object
// moved and the indirect light around it re-gathered. Prints what it measured; exit 1 on failure.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "shared/image.h"

namespace {

double luminance(const ag::Image& im, int x, int y) {
    const glm::vec3 c = im.rgb(x, y);
    return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
}

// Not blank: some light, and some contrast (a black or a flat frame fails).
int not_blank(const std::string& path) {
    const ag::Image im = ag::read_image(path);
    double sum = 0.0, sum2 = 0.0;
    const double n = double(im.width) * double(im.height);
    for (int y = 0; y < im.height; ++y)
        for (int x = 0; x < im.width; ++x) {
            const double l = luminance(im, x, y);
            sum += l;
            sum2 += l * l;
        }
    const double mean = sum / n, sd = std::sqrt(std::max(0.0, sum2 / n - mean * mean));
    std::printf("%s: %dx%d, mean luminance %.4f, standard deviation %.4f\n", path.c_str(), im.width,
                im.height, mean, sd);
    return mean > 0.01 && sd > 0.02 ? 0 : 1;
}

// Mean luminance change from A to B over a rectangle given in fractions of the image: at least
// `change` if it is positive (got brighter), at most `change` if negative (got darker).
int changed(const std::string& a_path, const std::string& b_path, double x0, double y0, double x1,
            double y1, double change) {
    const ag::Image a = ag::read_image(a_path), b = ag::read_image(b_path);
    if (a.width != b.width || a.height != b.height) {
        std::printf("%s and %s differ in size\n", a_path.c_str(), b_path.c_str());
        return 1;
    }
    const int xa = int(x0 * a.width), xb = int(x1 * a.width), ya = int(y0 * a.height),
              yb = int(y1 * a.height);
    double la = 0.0, lb = 0.0;
    int n = 0;
    for (int y = ya; y < yb; ++y)
        for (int x = xa; x < xb; ++x) {
            la += luminance(a, x, y);
            lb += luminance(b, x, y);
            ++n;
        }
    if (n == 0) return 1;
    const double delta = (lb - la) / n;
    std::printf(
        "region [%d,%d)x[%d,%d): mean luminance %.4f -> %.4f, change %+.4f (need %s %+.4f)\n", xa,
        xb, ya, yb, la / n, lb / n, delta, change >= 0 ? ">=" : "<=", change);
    return (change >= 0 ? delta >= change : delta <= change) ? 0 : 1;
}

// The dump after a drag: `object` selected, moved at least `min_move`, and at least `min_near`
// IIM texels near moved objects gathered after the first edit.
int dragged(const std::string& path, const std::string& object, double min_move, long min_near) {
    std::ifstream file(path);
    std::stringstream text;
    text << file.rdbuf();
    const nlohmann::json j = nlohmann::json::parse(text.str());
    int failures = 0;
    const std::string selected = j["selection"].value("object", std::string("(none)"));
    std::printf("selected object: %s\n", selected.c_str());
    failures += selected != object;
    bool found = false;
    for (const auto& o : j["objects"]) {
        if (o["name"] != object) continue;
        found = true;
        double d2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double d = o["position"][k].get<double>() - o["start_position"][k].get<double>();
            d2 += d * d;
        }
        std::printf("'%s' moved %.1f (need >= %.1f)\n", object.c_str(), std::sqrt(d2), min_move);
        failures += std::sqrt(d2) < min_move;
    }
    failures += !found;
    const long near = j["iim_texels_gathered"]["near_moved_objects_after_first_edit"].get<long>();
    std::printf(
        "IIM texels near moved objects gathered after the first edit: %ld (need >= %ld); "
        "interactive edits %d\n",
        near, min_near, j["edits"]["interactive"].get<int>());
    failures += near < min_near;
    failures += j["edits"]["interactive"].get<int>() < 1;
    return failures ? 1 : 0;
}

int usage() {
    std::fprintf(stderr,
                 "usage: viewer_check not-blank IMAGE\n"
                 "       viewer_check changed A B X0 Y0 X1 Y1 CHANGE   (rectangle in fractions of "
                 "the image;\n"
                 "                    CHANGE > 0: B brighter by at least it, < 0: darker by at "
                 "least -CHANGE)\n"
                 "       viewer_check dragged DUMP.json OBJECT MIN_MOVE MIN_NEAR_TEXELS\n");
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const std::string mode = argc > 1 ? argv[1] : "";
        if (mode == "not-blank" && argc == 3) return not_blank(argv[2]);
        if (mode == "changed" && argc == 9)
            return changed(argv[2], argv[3], std::atof(argv[4]), std::atof(argv[5]),
                           std::atof(argv[6]), std::atof(argv[7]), std::atof(argv[8]));
        if (mode == "dragged" && argc == 6)
            return dragged(argv[2], argv[3], std::atof(argv[4]), std::atol(argv[5]));
        return usage();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "viewer_check: %s\n", e.what());
        return 1;
    }
}
