#include "shared/script.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "deadline.h"
#include "external_scenes.h"
#include "shared/input_error.h"
#include "shared/scene_edit.h"
#include "shared/scene_file.h"
#include "temp_dir.h"

namespace ag {

namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::StartsWith;

const fs::path kScenes = fs::path(AG_SOURCE_DIR) / "scenes";

Scene small_scene() {
    Scene s;
    s.path = "small.json";
    s.objects.resize(2);
    s.objects[0].name = "cube";
    s.objects[0].transform.translation = {1, 2, 3};
    s.objects[0].dynamic = true;
    s.objects[1].name = "floor";
    s.lights.resize(2);
    s.lights[0].name = "lamp";
    s.lights[0].position = {0, 5, 0};
    s.lights[0].intensity = glm::vec3(10.0f);
    s.lights[1].name = "panel";
    s.lights[1].type = LightType::quad;
    s.lights[1].corners = {glm::vec3(0, 4, 0), glm::vec3(2, 4, 0), glm::vec3(2, 4, 2),
                           glm::vec3(0, 4, 2)};
    s.lights[1].radiance = glm::vec3(1.0f);
    s.camera.eye = {0, 0, 5};
    s.camera.target = {0, 0, 0};
    init_versions(s);
    return s;
}

Script script(const std::string& source, const ScriptLimits& limits = {}) {
    return Script::from_string(source, "test.lua", limits);
}

std::string error_of(const Script& s) { return s.last_error().value_or("(no error)"); }

// Runs on_start and frames 0..99 and expects no errors.
void run_frames(Script& s, Scene& scene, int frames = 100) {
    ASSERT_TRUE(s.on_start(scene)) << error_of(s);
    for (int f = 0; f < frames; ++f) ASSERT_TRUE(s.on_frame(scene, f, f / 30.0)) << error_of(s);
}

// The scene each example script is written for, by the script's name: cornell_* -> cornell.json,
// two_rooms_* -> two_rooms.json, conference_* -> conference.json, bumpy_133k_* ->
// bumpy_133k_box.json (bumpy_133k.json with a dynamic box).
fs::path scene_for(const fs::path& script_path) {
    const std::string name = script_path.stem().string();
    const struct {
        const char* prefix;
        const char* scene;
    } scenes[] = {{"cornell_", "cornell.json"},
                  {"two_rooms_", "two_rooms.json"},
                  {"conference_", "conference.json"},
                  {"sponza_", "sponza.json"},
                  {"bumpy_133k_", "bumpy_133k_box.json"},
                  {"cube_in_a_box", "cube_in_a_box.json"},
                  {"compare_edits", "compare.json"},
                  {"vpl_table_bunny", "vpl_table_bunny.json"},
                  {"vpl_table_torus", "vpl_table_torus.json"},
                  {"moving_light", "moving_light.json"},
                  {"spheres_66", "spheres_66.json"}};
    for (const auto& s : scenes)
        if (name.rfind(s.prefix, 0) == 0) return kScenes / s.scene;
    return {};
}

// A script's scene; meshes from ../shared/external-scenes (the conference room) are replaced by a
// stand-in box, so the scripts run whether or not that folder is there: they address objects and
// lights by name only.
Scene scene_for_script(const fs::path& script_path) {
    return test::load_scene_with_stand_ins(scene_for(script_path));
}

}  // namespace

// ---- the example scripts ----------------------------------------------------------------------

TEST(ScriptExamples, EveryExampleRunsAHundredFramesAndEditsItsScene) {
    int count = 0;
    for (const fs::directory_entry& entry : fs::directory_iterator(kScenes)) {
        if (entry.path().extension() != ".lua") continue;
        SCOPED_TRACE(entry.path().string());
        const fs::path scene_path = scene_for(entry.path());
        ASSERT_FALSE(scene_path.empty()) << "no scene known for this script; extend scene_for()";
        Scene scene = scene_for_script(entry.path());
        Script s(entry.path().string());
        run_frames(s, scene);
        EXPECT_GT(scene.version, 0u);
        EXPECT_FALSE(scene.changes.empty());
        ++count;
    }
    EXPECT_GE(count, 3);
}

// The step scripts edit their scene in exactly one frame (20), each with the one edit it names.
TEST(ScriptExamples, StepScriptsEditInOneFrame) {
    const struct {
        const char* script;
        ChangeKind kind;
    } steps[] = {{"cornell_cube_jump.lua", ChangeKind::object_transform},
                 {"two_rooms_door_step.lua", ChangeKind::object_transform},
                 {"two_rooms_light_off_step.lua", ChangeKind::light_enabled},
                 {"cornell_albedo_step.lua", ChangeKind::object_material},
                 {"conference_box_jump.lua", ChangeKind::object_transform},
                 {"bumpy_133k_jump.lua", ChangeKind::object_transform}};
    for (const auto& step : steps) {
        SCOPED_TRACE(step.script);
        Scene scene = scene_for_script(kScenes / step.script);
        Script s((kScenes / step.script).string());
        ASSERT_TRUE(s.on_start(scene)) << error_of(s);
        std::vector<int> edited;
        for (int f = 0; f < 100; ++f) {
            const uint64_t version = scene.version;
            ASSERT_TRUE(s.on_frame(scene, f, f / 30.0)) << error_of(s);
            if (scene.version != version) edited.push_back(f);
        }
        EXPECT_EQ(edited, std::vector<int>{20});
        ASSERT_EQ(scene.changes.size(), 1u);
        EXPECT_EQ(scene.changes[0].kind, step.kind);
    }
    // The jump lands where the slide ends.
    Scene jump = load_scene((kScenes / "cornell.json").string()), slide = jump;
    Script a((kScenes / "cornell_cube_jump.lua").string()),
        b((kScenes / "cornell_move_cube.lua").string());
    run_frames(a, jump, 61);
    run_frames(b, slide, 61);
    const int cube = jump.find_object("cube");
    EXPECT_LT(glm::length(jump.objects[size_t(cube)].transform.translation -
                          slide.objects[size_t(cube)].transform.translation),
              1e-3f);
}

TEST(ScriptExamples, CornellCubeSlidesThenStops) {
    Scene scene = load_scene((kScenes / "cornell.json").string());
    const int cube = scene.find_object("cube");
    ASSERT_GE(cube, 0);
    const glm::vec3 start = scene.objects[size_t(cube)].transform.translation;
    const glm::quat rotation = scene.objects[size_t(cube)].transform.rotation;
    Script s((kScenes / "cornell_move_cube.lua").string());
    run_frames(s, scene, 61);
    const glm::vec3 end = scene.objects[size_t(cube)].transform.translation;
    const uint64_t version = scene.version;
    EXPECT_GT(glm::length(end - start), 200.0f);  // across the floor
    EXPECT_FLOAT_EQ(end.y, start.y);              // on the floor
    EXPECT_LT(end.x + 103.0f, 555.0f);            // inside the room
    EXPECT_GT(end.z - 103.0f, 0.0f);
    EXPECT_NEAR(std::abs(glm::dot(scene.objects[size_t(cube)].transform.rotation, rotation)), 1.0f,
                1e-6f);  // slides, no turn
    for (int f = 61; f < 100; ++f) ASSERT_TRUE(s.on_frame(scene, f, f / 30.0)) << error_of(s);
    EXPECT_EQ(scene.version, version);  // stopped: no more edits
    EXPECT_EQ(scene.objects[size_t(cube)].transform.translation, end);
    for (const SceneChange& c : scene.changes) {  // only the cube moved
        EXPECT_EQ(c.kind, ChangeKind::object_transform);
        EXPECT_EQ(c.index, cube);
    }
}

TEST(ScriptExamples, DoorSwingsOpenAboutItsHinge) {
    Scene scene = load_scene((kScenes / "two_rooms.json").string());
    const int door = scene.find_object("door");
    ASSERT_GE(door, 0);
    const Transform before = scene.objects[size_t(door)].transform;
    Script s((kScenes / "two_rooms_open_door.lua").string());
    run_frames(s, scene, 10);
    EXPECT_EQ(scene.version, 0u);  // still shut before frame 10
    for (int f = 10; f < 100; ++f) ASSERT_TRUE(s.on_frame(scene, f, f / 30.0)) << error_of(s);
    const Transform after = scene.objects[size_t(door)].transform;
    EXPECT_EQ(after.translation, before.translation);  // turns about the hinge
    // The door's width (+z in object space) now points along +x: open by 90 degrees.
    const glm::vec3 width = after.apply_vector({0, 0, 1});
    EXPECT_NEAR(width.x, 1.0f, 1e-4f);
    EXPECT_NEAR(width.z, 0.0f, 1e-4f);
    EXPECT_NEAR(after.apply_vector({0, 1, 0}).y, 1.0f, 1e-5f);
    EXPECT_GE(scene.changes.size(), 30u);  // it swung over many frames
}

TEST(ScriptExamples, RoomALightsGoOffAndRoomBStaysLit) {
    Scene scene = load_scene((kScenes / "two_rooms.json").string());
    Script s((kScenes / "two_rooms_lights_off.lua").string());
    run_frames(s, scene);
    for (const char* name : {"a1", "a2"}) {
        const int i = scene.find_light(name);
        ASSERT_GE(i, 0) << name;
        EXPECT_FALSE(scene.lights[size_t(i)].enabled) << name;
    }
    for (const char* name : {"b1", "b2"}) {
        const int i = scene.find_light(name);
        ASSERT_GE(i, 0) << name;
        EXPECT_TRUE(scene.lights[size_t(i)].enabled) << name;
        EXPECT_EQ(scene.light_versions[size_t(i)], 0u) << name;
    }
    ASSERT_EQ(scene.changes.size(), 2u);  // switched once each
    EXPECT_EQ(scene.changes[0].kind, ChangeKind::light_enabled);
}

// ---- the API ---------------------------------------------------------------------------------

TEST(Script, EditsReachTheSceneThroughTheEditApi) {
    Scene scene = small_scene();
    Script s = script(R"(
        function on_frame(scene, frame, time)
            local cube = scene:object("cube")
            cube:translate(1, 0, 0)
            cube:set_albedo(0.5, 0.25, 0.125)
            scene:light("lamp"):move(0, 1, 0)
            scene:light("panel"):set_color(2, 2, 2)
            scene:light("panel"):set_enabled(false)
            scene:set_camera({fov_y = 60})
        end)");
    ASSERT_TRUE(s.on_frame(scene, 0, 0.0)) << error_of(s);
    EXPECT_EQ(scene.objects[0].transform.translation, glm::vec3(2, 2, 3));
    EXPECT_EQ(scene.objects[0].material.albedo, glm::vec3(0.5f, 0.25f, 0.125f));
    EXPECT_EQ(scene.lights[0].position, glm::vec3(0, 6, 0));
    EXPECT_EQ(scene.lights[1].radiance, glm::vec3(2.0f));
    EXPECT_FALSE(scene.lights[1].enabled);
    EXPECT_FLOAT_EQ(scene.camera.fov_y, 60.0f);
    EXPECT_EQ(scene.camera.eye, glm::vec3(0, 0, 5));  // fields left out keep their values
    EXPECT_EQ(scene.version, 6u);
    EXPECT_GT(scene.object_versions[0], 0u);
    EXPECT_EQ(scene.object_versions[1], 0u);
    EXPECT_GT(scene.camera_version, 0u);
}

TEST(Script, ReadsSeeTheCallsOwnEditsAndTheScene) {
    Scene scene = small_scene();
    Script s = script(R"(
        function on_frame(scene, frame, time)
            local cube = scene:object("cube")
            assert(cube:name() == "cube")
            local x, y, z = cube:position()
            assert(x == 1 and y == 2 and z == 3, "position")
            cube:set_position(4, 5, 6)
            x, y, z = cube:position()
            assert(x == 4 and y == 5 and z == 6, "staged position")
            local r, g, b = cube:albedo()
            assert(math.abs(r - 0.75) < 1e-6, "albedo")
            local panel = scene:light("panel")
            x, y, z = panel:position()
            assert(x == 1 and y == 4 and z == 1, "quad centre")
            assert(panel:enabled() == true and panel:name() == "panel")
            r, g, b = scene:light("lamp"):color()
            assert(r == 10 and g == 10 and b == 10, "intensity")
            local cam = scene:camera()
            assert(cam.eye[3] == 5 and cam.up[2] == 1 and math.abs(cam.fov_y - 40) < 1e-5)
            assert(scene:object("cube") == cube and scene:object("floor") ~= cube)
            assert(tostring(cube) == "object 'cube'", tostring(cube))
            assert(frame == 7 and time == 0.25)
        end)");
    ASSERT_TRUE(s.on_frame(scene, 7, 0.25)) << error_of(s);
    EXPECT_EQ(scene.objects[0].transform.translation, glm::vec3(4, 5, 6));
}

TEST(Script, HandlesAndGlobalsLastBetweenCalls) {
    Scene scene = small_scene();
    Script s = script(R"(
        local lamp
        count = 0
        function on_start(s) lamp = s:light("lamp") end
        function on_frame(s, frame) count = count + 1; lamp:set_color(count, count, count) end
    )");
    run_frames(s, scene, 3);
    EXPECT_EQ(scene.lights[0].intensity, glm::vec3(3.0f));
}

TEST(Script, MissingCallbacksAreNotErrors) {
    Scene scene = small_scene();
    Script s = script("x = 1");
    EXPECT_TRUE(s.on_start(scene));
    EXPECT_TRUE(s.on_frame(scene, 0, 0.0));
    EXPECT_FALSE(s.last_error());
    EXPECT_EQ(scene.version, 0u);
}

TEST(Script, TheGlobalSceneWorksOnlyInsideCallbacks) {
    Scene scene = small_scene();
    Script s = script("function on_frame() scene:object('cube'):translate(0, 1, 0) end");
    ASSERT_TRUE(s.on_frame(scene, 0, 0.0)) << error_of(s);
    EXPECT_EQ(scene.objects[0].transform.translation.y, 3.0f);
    try {
        script("\nlocal cube = scene:object('cube')");
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), StartsWith("test.lua:2: "));
        EXPECT_THAT(e.what(), HasSubstr("only available inside on_start and on_frame"));
    }
}

// ---- errors ----------------------------------------------------------------------------------

class ScriptFiles : public test::TempDirTest {};

TEST_F(ScriptFiles, SyntaxErrorNamesFileAndLine) {
    const std::string path = write("broken.lua", "function on_frame(scene)\n  x = = 1\nend\n");
    try {
        Script s(path);
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), StartsWith(path + ":2: "));  // the whole path, not Lua's 60 chars
        EXPECT_THAT(e.what(), HasSubstr("unexpected symbol"));
    }
}

TEST_F(ScriptFiles, LongPathsAreNotTruncated) {
    const std::string path =
        write(std::string(80, 'x') + ".lua", "function on_frame(scene)\n  error('boom')\nend\n");
    Script s(path);
    Scene scene = small_scene();
    EXPECT_FALSE(s.on_frame(scene, 0, 0.0));
    EXPECT_EQ(error_of(s), path + ":2: boom");
}

TEST_F(ScriptFiles, MissingFileIsAnInputError) {
    try {
        Script s(path("absent.lua"));
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), StartsWith(path("absent.lua") + ": cannot open script"));
    }
}

TEST_F(ScriptFiles, OnlyRegularFilesOfBoundedSizeAreRead) {
    fs::create_directories(path("dir.lua"));
    for (const std::string& bad : {path("dir.lua"), std::string("/dev/zero")}) {
        try {
            Script s(bad);
            FAIL() << "expected an InputError for " << bad;
        } catch (const InputError& e) {
            EXPECT_THAT(e.what(), StartsWith(bad + ": a script must be a regular file"));
        }
    }
    const std::string big = write("big.lua", "-- " + std::string(2 << 20, 'x') + "\n");
    try {
        Script s(big);
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), HasSubstr("larger than the limit"));
    }
}

// Finalizers run with hooks off, outside the budget: scripts cannot declare them.
TEST(Script, GcFinalizersAreRefused) {
    test::within_deadline(std::chrono::seconds(20), [] {
        try {
            script("setmetatable({}, {__gc = function() while true do end end})");
            ADD_FAILURE() << "expected an InputError";
        } catch (const InputError& e) {
            EXPECT_THAT(e.what(), StartsWith("test.lua:1: "));
            EXPECT_THAT(e.what(), HasSubstr("__gc"));
        }
    });
    Scene scene = small_scene();
    Script s = script(
        "function on_frame(scene)\n"
        "  local t = setmetatable({}, {__index = function() return 7 end})\n"
        "  assert(t.x == 7)\n"
        "  setmetatable({}, {__gc = false})\n"
        "end\n");
    EXPECT_FALSE(s.on_frame(scene, 0, 0.0));
    EXPECT_THAT(error_of(s), HasSubstr("test.lua:4: setmetatable: '__gc'"));
}

TEST(Script, LongAndControlCharacterMessagesAreSanitised) {
    Scene scene = small_scene();
    Script s = script(
        "function on_frame(scene)\n"
        "  error('\\27[31m' .. string.rep('x', 100000) .. '\\n\\27[0m')\n"
        "end\n");
    EXPECT_FALSE(s.on_frame(scene, 0, 0.0));
    const std::string error = error_of(s);
    EXPECT_LT(error.size(), 2200u);
    EXPECT_EQ(error.find('\x1b'), std::string::npos);
    EXPECT_THAT(error, HasSubstr("message truncated"));
}

TEST(Script, ErrorsInTopLevelCodeAreInputErrors) {
    try {
        script("local x = 1\nlocal y = nil + x\n");
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), StartsWith("test.lua:2: attempt to perform arithmetic"));
    }
    EXPECT_THROW(script("\x1bLua"), InputError);  // precompiled chunks are refused
}

TEST(Script, RuntimeErrorLeavesTheSceneUntouchedAndTheNextFrameRuns) {
    Scene scene = small_scene();
    Script s = script(R"(
        function on_frame(scene, frame)
            scene:object("cube"):translate(10, 0, 0)
            scene:light("lamp"):set_enabled(false)
            scene:set_camera({fov_y = 20})
            if frame == 0 then
                error("boom")
            end
        end)");
    EXPECT_FALSE(s.on_frame(scene, 0, 0.0));
    EXPECT_EQ(error_of(s), "test.lua:7: boom");
    EXPECT_EQ(s.error_count(), 1);
    // All or nothing: the edits before the error were never applied.
    EXPECT_EQ(scene.version, 0u);
    EXPECT_TRUE(scene.changes.empty());
    EXPECT_EQ(scene.objects[0].transform.translation, glm::vec3(1, 2, 3));
    EXPECT_TRUE(scene.lights[0].enabled);
    EXPECT_FLOAT_EQ(scene.camera.fov_y, 40.0f);

    EXPECT_TRUE(s.on_frame(scene, 1, 0.0)) << error_of(s);
    EXPECT_FALSE(s.last_error());
    EXPECT_EQ(s.error_count(), 1);
    EXPECT_EQ(scene.objects[0].transform.translation, glm::vec3(11, 2, 3));
    EXPECT_FALSE(scene.lights[0].enabled);
    EXPECT_EQ(scene.version, 3u);
}

TEST(Script, ErrorsWithoutAPositionGetOne) {
    Scene scene = small_scene();
    Script s = script(
        "function on_frame()\n  error({})\nend\n"
        "function on_start()\n  error('plain', 0)\nend\n");
    EXPECT_FALSE(s.on_frame(scene, 0, 0.0));
    EXPECT_EQ(error_of(s), "test.lua:2: (error object is a table value)");
    EXPECT_FALSE(s.on_start(scene));
    EXPECT_EQ(error_of(s), "test.lua:5: plain");
    Script t = script("on_frame = 3");
    EXPECT_FALSE(t.on_frame(scene, 0, 0.0));
    EXPECT_THAT(error_of(t), StartsWith("test.lua: global 'on_frame' must be a function"));
}

TEST(Script, SandboxRefusesSystemAccessAndTheNextFrameRuns) {
    const std::vector<std::string> attempts = {
        "os.execute('touch /tmp/ag_script_escaped')",
        "io.open('/etc/passwd')",
        "require('os')",
        "debug.sethook()",
        "dofile('/etc/passwd')",
        "loadfile('/etc/passwd')",
        "load('return 1')",
        "package.loadlib('libc.so.6', 'system')",
        "collectgarbage('stop')",
        "string.dump(print)",
        "getmetatable(scene).__index = nil",
    };
    for (const std::string& attempt : attempts) {
        SCOPED_TRACE(attempt);
        Scene scene = small_scene();
        Script s = script(
            "function on_frame(scene, frame)\n"
            "  if frame == 0 then " +
            attempt +
            " end\n"
            "  scene:object('cube'):translate(1, 0, 0)\n"
            "end\n");
        EXPECT_FALSE(s.on_frame(scene, 0, 0.0));
        EXPECT_THAT(error_of(s), StartsWith("test.lua:2: "));
        EXPECT_EQ(scene.version, 0u);
        EXPECT_TRUE(s.on_frame(scene, 1, 0.0)) << error_of(s);
        EXPECT_EQ(scene.objects[0].transform.translation.x, 2.0f);
    }
    EXPECT_FALSE(fs::exists("/tmp/ag_script_escaped"));

    Scene scene = small_scene();
    Script s = script("function on_frame() os.execute('true') end");
    EXPECT_FALSE(s.on_frame(scene, 0, 0.0));
    EXPECT_THAT(error_of(s), HasSubstr("'os' is not available: edit scripts run in a sandbox"));
    Script t = script(
        "function on_frame() return math.sin(1) + #string.rep('a', 3) + "
        "#table.concat({'a'}) + utf8.len('x') + select('#', coroutine.running()) end");
    EXPECT_TRUE(t.on_frame(scene, 0, 0.0)) << error_of(t);
}

TEST(Script, RunawayLoopStopsAtTheBudgetAndTheNextCallRuns) {
    Scene scene = small_scene();
    ScriptLimits limits;
    limits.instructions = 100'000;
    const std::vector<std::string> loops = {
        "while true do end",
        // pcall cannot swallow the budget error
        "while true do pcall(function() while true do end end) end",
        "local ok = pcall(function() while true do end end); x = 1",
        // nor can coroutines, which share the budget
        "while true do coroutine.resume(coroutine.create(function() while true do end end)) end",
        "local function f() return f() end f()",  // a tail call loop, no stack growth
    };
    for (const std::string& loop : loops) {
        SCOPED_TRACE(loop);
        Script s = script(
            "function on_frame(scene, frame)\n"
            "  scene:object('cube'):translate(1, 0, 0)\n"
            "  if frame == 0 then " +
                loop +
                " end\n"
                "end\n",
            limits);
        EXPECT_FALSE(s.on_frame(scene, 0, 0.0));
        EXPECT_THAT(error_of(s), StartsWith("test.lua:"));
        EXPECT_THAT(error_of(s), HasSubstr("instruction budget exceeded (100000 instructions)"));
        const glm::vec3 before = scene.objects[0].transform.translation;
        EXPECT_TRUE(s.on_frame(scene, 1, 0.0)) << error_of(s);
        EXPECT_EQ(scene.objects[0].transform.translation.x, before.x + 1.0f);
    }
}

// Lua's pattern matcher runs in C, out of the instruction hook's reach: forty "a*" against forty
// a's backtracked without end (afterglow render hung past 60 s; the budget never fired). find,
// match, gmatch and gsub, as functions and as string methods, bound their work first (100 steps
// per instruction of the budget) and fail naming themselves; everyday patterns still run, and the
// next frame runs.
TEST(Script, PatternsThatWouldBacktrackForeverAreRefused) {
    Scene scene = small_scene();
    const std::vector<std::string> calls = {
        "local s = ('a'):rep(40); return s:match(('a*'):rep(40) .. 'b')",
        "return string.find(('a'):rep(40), ('a-'):rep(40) .. 'b')",
        "for w in string.gmatch(('a'):rep(40), ('a?'):rep(40) .. 'b') do end",
        "return (('a'):rep(40)):gsub(('a+'):rep(40) .. 'b', 'x')",
        // a plain find of a long needle in a long haystack is n × m too
        "local s = ('a'):rep(2000000); return s:find(('a'):rep(1000000) .. 'b', 1, true)",
    };
    for (const std::string& call : calls) {
        SCOPED_TRACE(call);
        Script s = script(
            "function on_frame(scene, frame)\n"
            "  if frame == 0 then " +
            call +
            " end\n"
            "  scene:object('cube'):translate(1, 0, 0)\n"
            "end\n");
        test::within_deadline(std::chrono::seconds(20),
                              [&] { EXPECT_FALSE(s.on_frame(scene, 0, 0.0)); });
        EXPECT_THAT(error_of(s), HasSubstr("test.lua:2: string."));
        EXPECT_THAT(error_of(s), HasSubstr("over the budget of 10^9 (matching runs in C"));
        EXPECT_TRUE(s.on_frame(scene, 1, 0.0)) << error_of(s);
    }
    Script fine = script(
        "function on_frame(scene, frame)\n"
        "  assert(('lamp_3'):match('^lamp_(%d+)$') == '3')\n"
        "  assert(select(2, string.gsub(('a b  c'):rep(1000), '%s+', ' ')) == 2000)\n"
        "  assert(string.find('x.y', '.', 1, true) == 2)\n"
        "  local n = 0 for k, v in string.gmatch('a=1, b=2', '(%w+)=(%w+)') do n = n + 1 end\n"
        "  assert(n == 2)\n"
        "end\n");
    EXPECT_TRUE(fine.on_frame(scene, 0, 0.0)) << error_of(fine);
}

// A coroutine kept between frames (an animation, say) survives another frame's runaway loop.
TEST(Script, CoroutinesOutliveABudgetError) {
    Scene scene = small_scene();
    ScriptLimits limits;
    limits.instructions = 50'000;
    Script s = script(R"(
        local step = coroutine.wrap(function(cube)
            while true do
                for i = 1, 100 do end
                cube:translate(1, 0, 0)
                cube = coroutine.yield()
            end
        end)
        function on_frame(scene, frame)
            step(scene:object("cube"))
            if frame == 0 then
                while true do end
            end
        end)",
                      limits);
    EXPECT_FALSE(s.on_frame(scene, 0, 0.0));
    EXPECT_THAT(error_of(s), HasSubstr("instruction budget exceeded"));
    for (int f = 1; f <= 3; ++f) EXPECT_TRUE(s.on_frame(scene, f, 0.0)) << error_of(s);
    EXPECT_EQ(scene.objects[0].transform.translation.x, 4.0f);
}

TEST(Script, BudgetAlsoBoundsTopLevelCode) {
    ScriptLimits limits;
    limits.instructions = 10'000;
    try {
        script("local n = 0\nwhile true do n = n + 1 end", limits);
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), StartsWith("test.lua:2: instruction budget exceeded"));
    }
}

TEST(Script, MemoryBombStopsCleanlyAndTheNextFrameRuns) {
    Scene scene = small_scene();
    ScriptLimits limits;
    limits.memory_bytes = size_t(16) << 20;
    const std::vector<std::string> bombs = {
        "local t = {} while true do t[#t + 1] = string.rep('x', 1 << 20) .. #t end",
        "local s = string.rep('x', 1 << 30)",
        "local t = {} for i = 1, 1e9 do t[i] = i end",
    };
    for (const std::string& bomb : bombs) {
        SCOPED_TRACE(bomb);
        Script s = script(
            "function on_frame(scene, frame)\n"
            "  if frame == 0 then " +
                bomb +
                " end\n"
                "  scene:object('cube'):translate(1, 0, 0)\n"
                "end\n",
            limits);
        const glm::vec3 before = scene.objects[0].transform.translation;
        EXPECT_FALSE(s.on_frame(scene, 0, 0.0));
        EXPECT_THAT(error_of(s), StartsWith("test.lua"));
        EXPECT_THAT(error_of(s), HasSubstr("memory limit of 16 MiB exceeded"));
        EXPECT_TRUE(s.on_frame(scene, 1, 0.0)) << error_of(s);
        EXPECT_EQ(scene.objects[0].transform.translation.x, before.x + 1.0f);
    }
}

TEST(Script, WrongArgumentsGiveClearMessages) {
    struct Case {
        std::string call;
        std::string message;
    };
    const std::vector<Case> cases = {
        {"scene:object('nope')", "no object named 'nope' (the scene has: cube, floor)"},
        {"scene:light('cube')", "no light named 'cube' (the scene has: lamp, panel)"},
        {"scene:object()", "bad argument #1 to 'object' (string expected, got no value)"},
        {"cube:set_position('a', 1, 2)",
         "bad argument #1 to 'set_position' (number expected, got string)"},
        {"cube:set_position(1, 2)",
         "bad argument #3 to 'set_position' (number expected, got no value)"},
        {"cube:set_position(1, 2, 3, 4)", "'set_position' takes 3 arguments, got 4"},
        {"cube:translate(0/0, 0, 0)", "bad argument #1 to 'translate' (expected a finite number)"},
        {"cube:translate(0, math.huge, 0)",
         "bad argument #2 to 'translate' (expected a finite number)"},
        {"cube:translate(0, 1e300, 0)",
         "bad argument #2 to 'translate' (expected a finite number)"},
        {"cube:rotate(0, 0, 0, 45)", "rotate_object: expected a non-zero axis and finite degrees"},
        {"cube:set_albedo(2, 0, 0)", "set_albedo: expected albedo components in [0, 1]"},
        {"cube.position()", "bad argument #1 to 'position' (ag.Object expected, got no value)"},
        {"cube.position(scene:light('lamp'))",
         "bad argument #1 to 'position' (ag.Object expected, got ag.Light)"},
        {"scene:light('lamp'):set_enabled(1)",
         "bad argument #1 to 'set_enabled' (boolean expected, got number)"},
        {"scene:light('lamp'):set_color(-1, 0, 0)",
         "set_light_color: expected non-negative intensity"},
        {"scene:set_camera({fov = 30})",
         "unknown camera field 'fov' (expected eye, target, up, fov_y)"},
        {"scene:set_camera({eye = {1, 2}})",
         "camera field 'eye': expected a table of 3 numbers {x, y, z}"},
        {"scene:set_camera({up = {0, 'a', 0}})",
         "camera field 'up': element 2 is not a finite number"},
        {"scene:set_camera({fov_y = 200})", "set_camera: fov_y: expected a number in [0.1, 179]"},
        {"scene:set_camera({target = {0, 0, 5}})",
         "set_camera: target: expected a target different from the eye"},
        {"scene:set_camera({eye = {0, 0, 3e38}})",
         "set_camera: eye: expected coordinates within ±10000000 (the world-size limit)"},
        {"scene:light('lamp'):set_position(2^63, 500, 200)",
         "set_light_position: expected coordinates within ±10000000"},
        {"scene:light('lamp'):move(0, 2^63, 0)",
         "set_light_position: expected coordinates within ±10000000"},
        {"scene:light('lamp'):set_color(3e38, 1, 1)",
         "set_light_color: expected components in [0, 1e+15]"},
        {"cube:set_position(1e20, 82.5, 169)",
         "set_object_transform: object 'cube': expected the placed object within ±10000000"},
        {"scene:object('floor'):set_position(1, 2, 3)",
         "set_position: object 'floor' is static; mark it \"dynamic\": true in the scene to move "
         "it"},
        {"scene:object('floor'):translate(1, 2, 3)", "translate: object 'floor' is static"},
        {"scene:object('floor'):rotate(0, 1, 0, 5)", "rotate: object 'floor' is static"},
        {"scene:set_camera(5)", "bad argument #1 to 'set_camera' (table expected, got number)"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.call);
        Scene scene = small_scene();
        Script s = script(
            "function on_frame(scene)\n"
            "  local cube = scene:object('cube')\n"
            "  " +
            c.call +
            "\n"
            "end\n");
        EXPECT_FALSE(s.on_frame(scene, 0, 0.0));
        EXPECT_THAT(error_of(s), StartsWith("test.lua:3: " + c.message));
        EXPECT_EQ(scene.version, 0u);
    }
}

TEST(Script, AScriptCanCatchAnEditErrorAndGoOn) {
    Scene scene = small_scene();
    Script s = script(R"(
        function on_frame(scene)
            local cube = scene:object("cube")
            local ok, message = pcall(cube.set_albedo, cube, 5, 0, 0)
            assert(not ok and message:find("albedo components"), message)
            cube:set_albedo(0.5, 0.5, 0.5)
        end)");
    EXPECT_TRUE(s.on_frame(scene, 0, 0.0)) << error_of(s);
    EXPECT_EQ(scene.objects[0].material.albedo, glm::vec3(0.5f));
    EXPECT_EQ(scene.version, 1u);
}

TEST(Script, ScriptsCanBeMovedAndKeepTheirState) {
    Scene scene = small_scene();
    Script a =
        script("n = 0\nfunction on_frame(s) n = n + 1; s:object('cube'):set_position(n, 0, 0) end");
    ASSERT_TRUE(a.on_frame(scene, 0, 0.0));
    Script b = std::move(a);
    ASSERT_TRUE(b.on_frame(scene, 1, 0.0)) << error_of(b);
    EXPECT_EQ(scene.objects[0].transform.translation.x, 2.0f);
    EXPECT_EQ(b.path(), "test.lua");
}

}  // namespace ag
