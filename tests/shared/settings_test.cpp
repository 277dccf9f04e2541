// Settings: effective texel size, JSON round trip, and the reader's error messages.
#include "shared/settings.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "shared/input_error.h"
#include "shared/settings_json.h"

namespace ag {
namespace {

using Json = nlohmann::json;

std::string read_error(const Json& json) {
    Settings s;
    try {
        read_settings(json, s, "scene.json", "/settings");
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

TEST(Settings, EffectiveTexelSizeDefaultsToATenthOfTheScene) {
    Settings s;
    EXPECT_FLOAT_EQ(effective_texel_size(s, 555.0f), 55.5f);
    s.lightmap.texel_size = 20.0f;
    EXPECT_FLOAT_EQ(effective_texel_size(s, 555.0f), 20.0f);
}

TEST(Settings, JsonRoundTripKeepsEveryField) {
    Settings s;
    s.photons.groups = 5;
    s.photons.path_tolerance = 0.25f;
    s.lightmap.texel_size = 111.0f;
    s.gather.backend = GatherBackend::cpu;
    s.gather.border_correction = BorderCorrection::none;
    s.direct.shadows = false;
    s.seed = 4000000000u;
    const Json json = settings_to_json_value(s);
    EXPECT_EQ(json["gather"]["backend"], "cpu");
    EXPECT_EQ(json["photons"]["path_tolerance"], 0.25);
    EXPECT_EQ(json["seed"], 4000000000u);
    EXPECT_EQ(Json(1e-4), settings_to_json_value(Settings{})["photons"]["path_tolerance"])
        << "floats print in their shortest form";

    Settings back;
    read_settings(json, back, "x.json", "/settings");
    EXPECT_EQ(settings_to_json_value(back), json);
    EXPECT_EQ(Json::parse(settings_to_json(s)), json);
}

TEST(Settings, AbsentFieldsKeepTheirValues) {
    Settings s;
    s.aim.knn = 77;
    read_settings(Json::parse(R"({"photons": {"groups": 3}})"), s, "x.json", "/settings");
    EXPECT_EQ(s.photons.groups, 3);
    EXPECT_EQ(s.aim.knn, 77);
}

TEST(Settings, ErrorsNameThePathAndWhatWasExpected) {
    struct Case {
        const char* json;
        const char* path;
        const char* expected;
    };
    const Case cases[] = {
        {R"({"photons": {"gropus": 3}})", "/settings/photons/gropus",
         "unknown key; expected one of groups, photons_per_group, max_bounces"},
        {R"({"photon": {}})", "/settings/photon", "expected one of seed, threads, photons"},
        {R"({"photons": 3})", "/settings/photons", "expected an object"},
        {R"({"photons": {"groups": "many"}})", "/settings/photons/groups",
         "expected an integer in [1, 1000000], got the string \"many\""},
        {R"({"photons": {"groups": 2.5}})", "/settings/photons/groups", "got 2.5"},
        {R"({"photons": {"groups": 0}})", "/settings/photons/groups", "[1, 1000000], got 0"},
        {R"({"lightmap": {"crease_angle": 181}})", "/settings/lightmap/crease_angle",
         "expected a number in [0, 180], got 181"},
        {R"({"lightmap": {"texel_size": 1e300}})", "/settings/lightmap/texel_size",
         "expected a finite number"},
        {R"({"gather": {"backend": "opengl"}})", "/settings/gather/backend",
         "expected one of auto, gl, cpu, got \"opengl\""},
        {R"({"direct": {"shadows": 1}})", "/settings/direct/shadows", "expected true or false"},
        {R"({"seed": -1})", "/settings/seed", "expected an integer in [0, 4294967295]"},
        {R"([1, 2])", "/settings", "expected an object"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.json);
        const std::string err = read_error(Json::parse(c.json));
        EXPECT_NE(err.find(std::string("scene.json: ") + c.path + ": "), std::string::npos) << err;
        EXPECT_NE(err.find(c.expected), std::string::npos) << err;
    }
    // 2.0 is an integer written as a float; accept it.
    EXPECT_EQ(read_error(Json::parse(R"({"photons": {"groups": 2.0}})")), "");
}

}  // namespace
}  // namespace ag
