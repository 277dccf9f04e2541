#include "shared/script.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <lua.hpp>
#include <new>
#include <sstream>
#include <vector>

#include "shared/input_error.h"
#include "shared/scene_edit.h"

// Lua reports errors with longjmp, which skips C++ destructors. So every C function below keeps
// only trivially destructible locals (PODs, references, glm vectors) while it may raise a Lua
// error, and runs C++ that may throw inside guarded(), which turns the exception into a plain
// message before lua_error is called. All Lua work from C++ happens inside lua_pcall.

namespace ag {

namespace {

constexpr const char* kSceneType = "ag.Scene";
constexpr const char* kObjectType = "ag.Object";
constexpr const char* kLightType = "ag.Light";
constexpr const char* kSceneKey = "ag.scene";        // registry slot of the one scene userdata
constexpr size_t kMaxScriptBytes = size_t(1) << 20;  // script files, checked before reading
constexpr size_t kMaxMessageChars = 2000;            // script errors as shown to users
constexpr int kHookStep = 1000;  // instructions between budget checks (~3% cost)

// Left out of the sandbox. Naming one raises an error that says why, rather than the puzzling
// "attempt to index a nil value".
constexpr std::array kBlockedGlobals = {"io",     "os",       "package", "require",       "debug",
                                        "dofile", "loadfile", "load",    "collectgarbage"};

// What a callback edited, per item, so the commit makes one scene_edit call per item and kind.
constexpr uint8_t kTransformEdit = 1;  // objects
constexpr uint8_t kMaterialEdit = 2;
constexpr uint8_t kPositionEdit = 1;  // lights
constexpr uint8_t kPowerEdit = 2;
constexpr uint8_t kEnabledEdit = 4;

}  // namespace

class ScriptState {
public:
    std::string path;                 // the file (or chunk name) as the user gave it
    std::string chunk_name;           // "@" + path
    char short_src[LUA_IDSIZE] = {};  // how Lua abbreviates `path` in its messages
    ScriptLimits limits;
    int hook_step = kHookStep;
    lua_State* L = nullptr;

    size_t memory_used = 0;
    bool memory_refused = false;  // the allocator said no since the last protected_run
    int64_t instructions_used = 0;
    int last_line = 0;  // line seen at the latest budget check, for memory errors

    // Bound only during a callback. Edits go to `staging` (a copy of the editable state, meshes
    // left out) through scene_edit.h, so they are validated exactly as on the real scene; commit()
    // replays them on the real scene once the callback has returned without error.
    Scene* scene = nullptr;
    bool staged = false;
    Scene staging;
    std::vector<uint8_t> object_edits;
    std::vector<uint8_t> light_edits;
    bool camera_edited = false;

    std::optional<std::string> last_error;
    int error_count = 0;

    ~ScriptState() {
        if (L) lua_close(L);
    }

    const Scene& view() const { return staged ? staging : *scene; }
    void begin_staging();
    void commit(Scene& target) const;

    std::optional<std::string> protected_run(lua_CFunction body, void* payload);
    void collect_garbage();
    bool call(Scene& target, const char* callback, bool with_frame, int frame, double time);
    std::string located(const std::string& message) const;
    std::string memory_message() const;
};

void ScriptState::begin_staging() {
    if (staged) return;
    const Scene& real = *scene;
    staging.path.clear();  // scene_edit's messages then start ": what: ..."; guarded() trims it
    staging.objects.resize(real.objects.size());
    for (size_t i = 0; i < real.objects.size(); ++i) {
        staging.objects[i].name = real.objects[i].name;
        staging.objects[i].material = real.objects[i].material;
        staging.objects[i].transform = real.objects[i].transform;
        staging.objects[i].dynamic = real.objects[i].dynamic;
        // The placement check needs only the object's radius; one vertex at that distance stands
        // in for the mesh, which staging does not copy.
        staging.objects[i].mesh.positions.assign(
            1, glm::vec3(object_radius(real.objects[i].mesh), 0.0f, 0.0f));
    }
    staging.lights = real.lights;
    staging.camera = real.camera;
    staging.changes.clear();
    init_versions(staging);
    object_edits.assign(real.objects.size(), 0);
    light_edits.assign(real.lights.size(), 0);
    camera_edited = false;
    staged = true;
}

// The staged values already passed scene_edit's checks, so these calls cannot reject them.
void ScriptState::commit(Scene& target) const {
    for (size_t i = 0; i < object_edits.size(); ++i) {
        const Object& o = staging.objects[i];
        if (object_edits[i] & kTransformEdit) set_object_transform(target, int(i), o.transform);
        if (object_edits[i] & kMaterialEdit) set_albedo(target, int(i), o.material.albedo);
    }
    for (size_t i = 0; i < light_edits.size(); ++i) {
        const Light& l = staging.lights[i];
        if (light_edits[i] & kPositionEdit) set_light_position(target, int(i), l.center());
        if (light_edits[i] & kPowerEdit) set_light_color(target, int(i), l.value());
        if (light_edits[i] & kEnabledEdit) set_light_enabled(target, int(i), l.enabled);
    }
    if (camera_edited) set_camera(target, staging.camera);
}

// Lua's own messages start with short_src, which it truncates to 60 characters; show the whole
// path instead, and make sure every message names the file.
std::string ScriptState::located(const std::string& message) const {
    const size_t n = std::strlen(short_src);
    if (n > 0 && message.compare(0, n, short_src) == 0 && message.size() > n && message[n] == ':')
        return path + message.substr(n);
    if (message.compare(0, path.size(), path) == 0) return message;
    return path + ": " + message;
}

std::string ScriptState::memory_message() const {
    if (!memory_refused) return path + ": out of memory";
    const size_t mib = size_t(1) << 20;
    const std::string limit = limits.memory_bytes % mib == 0
                                  ? std::to_string(limits.memory_bytes / mib) + " MiB"
                                  : std::to_string(limits.memory_bytes) + " bytes";
    // Lua raises memory errors without a position; the line of the latest budget check is the
    // best available (the hook runs every kHookStep instructions).
    if (last_line > 0)
        return path + ":" + std::to_string(last_line) + ": memory limit of " + limit +
               " exceeded (near this line)";
    return path + ": memory limit of " + limit + " exceeded";
}

namespace {

ScriptState& state_of(lua_State* L) {
    void* ud = nullptr;
    lua_getallocf(L, &ud);
    return *static_cast<ScriptState*>(ud);
}

// ---- interpreter plumbing -------------------------------------------------------------------

// Counts memory against the limit; Lua turns a refusal into a memory error.
void* allocate(void* ud, void* ptr, size_t osize, size_t nsize) {
    ScriptState& s = *static_cast<ScriptState*>(ud);
    const size_t old_size = ptr ? osize : 0;
    if (nsize == 0) {
        std::free(ptr);
        s.memory_used -= old_size;
        return nullptr;
    }
    const size_t room = s.limits.memory_bytes - std::min(s.memory_used, s.limits.memory_bytes);
    if (nsize > old_size && nsize - old_size > room) {
        s.memory_refused = true;
        return nullptr;
    }
    void* p = std::realloc(ptr, nsize);
    if (p) s.memory_used = s.memory_used - old_size + nsize;
    return p;
}

// The instruction budget. Coroutines inherit the hook and share the one counter. Once the budget
// is spent the hook fires on every instruction of the thread, so a script cannot pcall its way
// past the error: the first instruction after any catch fails again.
void count_hook(lua_State* L, lua_Debug* ar) {
    ScriptState& s = state_of(L);
    const int step = lua_gethookcount(L);
    s.instructions_used += step;
    if (lua_getinfo(L, "Sl", ar) != 0 && ar->currentline > 0) s.last_line = ar->currentline;
    if (s.instructions_used < s.limits.instructions) {
        // A coroutine left at step 1 by an earlier callback's exhaustion goes back to normal.
        if (step != s.hook_step) lua_sethook(L, count_hook, LUA_MASKCOUNT, s.hook_step);
        return;
    }
    if (step != 1) lua_sethook(L, count_hook, LUA_MASKCOUNT, 1);
    lua_pushfstring(L, "%s:%d: instruction budget exceeded (%I instructions)", ar->short_src,
                    ar->currentline, lua_Integer(s.limits.instructions));
    lua_error(L);
}

// Gives every error message a position: errors without one (error(x, 0), non-string error
// objects) get the innermost script line on the stack.
int message_handler(lua_State* L) {
    const ScriptState& s = state_of(L);
    if (lua_type(L, 1) != LUA_TSTRING) {
        lua_pushfstring(L, "(error object is a %s value)", luaL_typename(L, 1));
        lua_replace(L, 1);
    }
    const char* message = lua_tostring(L, 1);
    const size_t n = std::strlen(s.short_src);
    if (n > 0 && std::strncmp(message, s.short_src, n) == 0 && message[n] == ':') return 1;
    lua_Debug ar;
    for (int level = 1; lua_getstack(L, level, &ar) != 0; ++level) {
        if (lua_getinfo(L, "Sl", &ar) != 0 && ar.currentline > 0) {
            lua_pushfstring(L, "%s:%d: %s", ar.short_src, ar.currentline, message);
            return 1;
        }
    }
    return 1;
}

// Lua's pattern matcher runs in C, where the instruction hook never fires: ("a"):rep(40):match(
// ("a*"):rep(40) .. "b") backtracks for longer than the universe lasts. string.find, match, gmatch
// and gsub therefore check a bound on their work first: a subject of n bytes and a pattern of m
// bytes with k repetition items (*, +, -, ?, counted wherever they stand, so sets overcount) take
// at most (n + 1) starts (1 if anchored by ^) × m × (n + 1)^k steps; a plain find (n + 1) × m. Up
// to kPatternStepsPerInstruction × the instruction budget (10^9 steps by default, about a second)
// runs as Lua's own; more is an error naming the function.
constexpr double kPatternStepsPerInstruction = 100.0;

int bounded_pattern(lua_State* L) {
    const char* name = lua_tostring(L, lua_upvalueindex(2));
    size_t n = 0, m = 0;
    luaL_checklstring(L, 1, &n);
    const char* p = luaL_checklstring(L, 2, &m);
    const bool plain = std::strcmp(name, "find") == 0 && lua_toboolean(L, 4);
    int k = 0;
    double log_steps = std::log(double(n) + 1.0) + std::log(double(m) + 1.0);
    if (!plain) {
        for (size_t i = 0; i < m; ++i) {
            if (p[i] == '%')
                ++i;  // an escaped character or a class: not a repetition item
            else if (p[i] == '*' || p[i] == '+' || p[i] == '-' || p[i] == '?')
                ++k;
        }
        if (m > 0 && p[0] == '^') log_steps -= std::log(double(n) + 1.0);
        log_steps += double(k) * std::log(double(n) + 1.0);
    }
    const double budget =
        kPatternStepsPerInstruction * double(std::max<int64_t>(state_of(L).limits.instructions, 1));
    if (log_steps > std::log(budget)) {
        char message[320];  // lua_pushfstring has no precision for %f
        std::snprintf(message, sizeof message,
                      "string.%s: a pattern of %d repetition items over a subject of %zu bytes may "
                      "take up to 10^%.0f steps, over the budget of 10^%.0f (matching runs in C, "
                      "outside the instruction budget); expected a simpler pattern or a shorter "
                      "string",
                      name, k, n, log_steps / std::log(10.0), std::log10(budget));
        return luaL_error(L, "%s", message);
    }
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_insert(L, 1);
    lua_call(L, lua_gettop(L) - 1, LUA_MULTRET);
    return lua_gettop(L);
}

int blocked_global(lua_State* L) {
    if (lua_type(L, 2) == LUA_TSTRING) {
        const char* key = lua_tostring(L, 2);
        for (const char* name : kBlockedGlobals)
            if (std::strcmp(key, name) == 0)
                return luaL_error(L,
                                  "'%s' is not available: edit scripts run in a sandbox without "
                                  "io, os, package, require, debug, dofile, loadfile, load and "
                                  "collectgarbage (docs/scripting.md)",
                                  key);
    }
    return 0;  // other unknown globals are nil, as usual
}

// Finalizers run with debug hooks off (in collections and in lua_close), out of reach of the
// instruction budget, so scripts cannot declare them: setmetatable refuses a __gc field (Lua marks
// an object for finalization only if __gc is there when the metatable is set).
int setmetatable_without_gc(lua_State* L) {
    if (lua_type(L, 2) == LUA_TTABLE) {
        lua_pushliteral(L, "__gc");
        if (lua_rawget(L, 2) != LUA_TNIL)
            return luaL_error(L,
                              "setmetatable: '__gc' finalizers are not available to scripts "
                              "(they would run outside the instruction budget)");
        lua_pop(L, 1);
    }
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_insert(L, 1);
    lua_call(L, lua_gettop(L) - 1, LUA_MULTRET);
    return lua_gettop(L);
}

// Script messages reach terminals and logs: bounded length, control characters made visible.
std::string printable(const std::string& message) {
    std::string out;
    out.reserve(std::min(message.size(), kMaxMessageChars) + 64);
    for (size_t i = 0; i < message.size() && out.size() < kMaxMessageChars; ++i) {
        const unsigned char c = (unsigned char)message[i];
        out += (c < 0x20 && c != '\n' && c != '\t') || c == 0x7f ? '?' : char(c);
    }
    if (out.size() < message.size())
        out += "... (message truncated: " + std::to_string(message.size()) + " characters)";
    return out;
}

// print() goes to stderr with the script position, keeping stdout free for the program's output.
int print_to_stderr(lua_State* L) {
    const int n = lua_gettop(L);
    luaL_Buffer b;
    luaL_buffinit(L, &b);
    luaL_where(L, 1);
    luaL_addvalue(&b);
    for (int i = 1; i <= n; ++i) {
        if (i > 1) luaL_addchar(&b, '\t');
        luaL_tolstring(L, i, nullptr);
        luaL_addvalue(&b);
    }
    luaL_addchar(&b, '\n');
    luaL_pushresult(&b);
    size_t length = 0;
    const char* text = lua_tolstring(L, -1, &length);
    std::fwrite(text, 1, length, stderr);
    return 0;
}

// ---- argument checks ------------------------------------------------------------------------

ScriptState& active(lua_State* L) {
    ScriptState& s = state_of(L);
    if (!s.scene) luaL_error(L, "the scene is only available inside on_start and on_frame");
    return s;
}

// Extra arguments are almost always a mistake (a colour passed to translate, say).
void check_arg_count(lua_State* L, int expected) {
    const int given = lua_gettop(L) - 1;  // after self
    if (given <= expected) return;
    lua_Debug ar;
    const char* name = "?";
    if (lua_getstack(L, 0, &ar) != 0 && lua_getinfo(L, "n", &ar) != 0 && ar.name) name = ar.name;
    luaL_error(L, "'%s' takes %d argument%s, got %d", name, expected, expected == 1 ? "" : "s",
               given);
}

bool finite_float(lua_Number v) { return std::abs(v) <= std::numeric_limits<float>::max(); }

float check_float(lua_State* L, int arg) {
    const lua_Number v = luaL_checknumber(L, arg);
    if (!finite_float(v)) luaL_argerror(L, arg, "expected a finite number");
    return float(v);
}

glm::vec3 check_vec3(lua_State* L, int first) {
    return {check_float(L, first), check_float(L, first + 1), check_float(L, first + 2)};
}

void push_vec3(lua_State* L, const glm::vec3& v) {
    lua_pushnumber(L, v.x);
    lua_pushnumber(L, v.y);
    lua_pushnumber(L, v.z);
}

// Runs a scene edit (C++ that may throw) from a C function. The message is copied to a plain
// buffer so that the exception and every C++ object are gone before lua_error longjmps.
template <class Edit>
void guarded(lua_State* L, const Edit& edit) {
    char message[512] = {};
    try {
        edit();
        return;
    } catch (const InputError& e) {
        const char* text = e.what();
        if (std::strncmp(text, ": ", 2) == 0) text += 2;  // the staging scene has no path
        std::snprintf(message, sizeof message, "%s", text);
    } catch (const std::bad_alloc&) {
        std::snprintf(message, sizeof message, "out of memory");
    } catch (const std::exception& e) {
        std::snprintf(message, sizeof message, "%s", e.what());
    }
    luaL_error(L, "%s", message);
}

// ---- object and light handles ---------------------------------------------------------------

struct Handle {
    int index;
};

void push_handle(lua_State* L, const char* type, int index) {
    auto* h = static_cast<Handle*>(lua_newuserdatauv(L, sizeof(Handle), 0));
    h->index = index;
    luaL_setmetatable(L, type);
}

size_t check_object(lua_State* L, const ScriptState& s) {
    const auto* h = static_cast<const Handle*>(luaL_checkudata(L, 1, kObjectType));
    if (h->index < 0 || size_t(h->index) >= s.view().objects.size())
        luaL_error(L, "object handle %d does not belong to this scene", h->index);
    return size_t(h->index);
}

size_t check_light(lua_State* L, const ScriptState& s) {
    const auto* h = static_cast<const Handle*>(luaL_checkudata(L, 1, kLightType));
    if (h->index < 0 || size_t(h->index) >= s.view().lights.size())
        luaL_error(L, "light handle %d does not belong to this scene", h->index);
    return size_t(h->index);
}

int handle_tostring(lua_State* L) {
    const ScriptState& s = state_of(L);
    const bool object = luaL_testudata(L, 1, kObjectType) != nullptr;
    const auto* h = static_cast<const Handle*>(object ? lua_touserdata(L, 1)
                                                      : luaL_checkudata(L, 1, kLightType));
    const char* kind = object ? "object" : "light";
    const size_t count = !s.scene ? 0 : object ? s.view().objects.size() : s.view().lights.size();
    if (h->index >= 0 && size_t(h->index) < count) {
        const std::string& name = object ? s.view().objects[size_t(h->index)].name
                                         : s.view().lights[size_t(h->index)].name;
        lua_pushfstring(L, "%s '%s'", kind, name.c_str());
    } else {
        lua_pushfstring(L, "%s #%d", kind, h->index);
    }
    return 1;
}

int handle_eq(lua_State* L) {
    const void* a_object = luaL_testudata(L, 1, kObjectType);
    const void* b_object = luaL_testudata(L, 2, kObjectType);
    const void* a_light = luaL_testudata(L, 1, kLightType);
    const void* b_light = luaL_testudata(L, 2, kLightType);
    const void* a = a_object ? a_object : a_light;
    const void* b = b_object ? b_object : b_light;
    lua_pushboolean(
        L, a && b && (a_object != nullptr) == (b_object != nullptr) &&
               static_cast<const Handle*>(a)->index == static_cast<const Handle*>(b)->index);
    return 1;
}

int object_name(lua_State* L) {
    const ScriptState& s = active(L);
    const size_t i = check_object(L, s);
    check_arg_count(L, 0);
    const std::string& name = s.view().objects[i].name;
    lua_pushlstring(L, name.data(), name.size());
    return 1;
}

int object_position(lua_State* L) {
    const ScriptState& s = active(L);
    const size_t i = check_object(L, s);
    check_arg_count(L, 0);
    push_vec3(L, s.view().objects[i].transform.translation);
    return 3;
}

int object_set_position(lua_State* L) {
    ScriptState& s = active(L);
    const size_t i = check_object(L, s);
    check_arg_count(L, 3);
    const glm::vec3 p = check_vec3(L, 2);
    guarded(L, [&] {
        s.begin_staging();
        check_movable(s.staging, int(i), "set_position");
        Transform t = s.staging.objects[i].transform;
        t.translation = p;
        set_object_transform(s.staging, int(i), t);
        s.object_edits[i] |= kTransformEdit;
    });
    return 0;
}

int object_translate(lua_State* L) {
    ScriptState& s = active(L);
    const size_t i = check_object(L, s);
    check_arg_count(L, 3);
    const glm::vec3 d = check_vec3(L, 2);
    guarded(L, [&] {
        s.begin_staging();
        check_movable(s.staging, int(i), "translate");
        translate_object(s.staging, int(i), d);
        s.object_edits[i] |= kTransformEdit;
    });
    return 0;
}

int object_rotate(lua_State* L) {
    ScriptState& s = active(L);
    const size_t i = check_object(L, s);
    check_arg_count(L, 4);
    const glm::vec3 axis = check_vec3(L, 2);
    const float degrees = check_float(L, 5);
    guarded(L, [&] {
        s.begin_staging();
        check_movable(s.staging, int(i), "rotate");
        rotate_object(s.staging, int(i), axis, degrees);
        s.object_edits[i] |= kTransformEdit;
    });
    return 0;
}

int object_albedo(lua_State* L) {
    const ScriptState& s = active(L);
    const size_t i = check_object(L, s);
    check_arg_count(L, 0);
    push_vec3(L, s.view().objects[i].material.albedo);
    return 3;
}

int object_set_albedo(lua_State* L) {
    ScriptState& s = active(L);
    const size_t i = check_object(L, s);
    check_arg_count(L, 3);
    const glm::vec3 albedo = check_vec3(L, 2);
    guarded(L, [&] {
        s.begin_staging();
        set_albedo(s.staging, int(i), albedo);
        s.object_edits[i] |= kMaterialEdit;
    });
    return 0;
}

int light_name(lua_State* L) {
    const ScriptState& s = active(L);
    const size_t i = check_light(L, s);
    check_arg_count(L, 0);
    const std::string& name = s.view().lights[i].name;
    lua_pushlstring(L, name.data(), name.size());
    return 1;
}

int light_position(lua_State* L) {
    const ScriptState& s = active(L);
    const size_t i = check_light(L, s);
    check_arg_count(L, 0);
    push_vec3(L, s.view().lights[i].center());
    return 3;
}

void stage_light_position(lua_State* L, ScriptState& s, size_t i, const glm::vec3& offset,
                          bool relative) {
    guarded(L, [&] {
        s.begin_staging();
        const glm::vec3 base = relative ? s.staging.lights[i].center() : glm::vec3(0.0f);
        set_light_position(s.staging, int(i), base + offset);
        s.light_edits[i] |= kPositionEdit;
    });
}

int light_set_position(lua_State* L) {
    ScriptState& s = active(L);
    const size_t i = check_light(L, s);
    check_arg_count(L, 3);
    stage_light_position(L, s, i, check_vec3(L, 2), false);
    return 0;
}

int light_move(lua_State* L) {
    ScriptState& s = active(L);
    const size_t i = check_light(L, s);
    check_arg_count(L, 3);
    stage_light_position(L, s, i, check_vec3(L, 2), true);
    return 0;
}

int light_color(lua_State* L) {
    const ScriptState& s = active(L);
    const size_t i = check_light(L, s);
    check_arg_count(L, 0);
    const Light& l = s.view().lights[i];
    push_vec3(L, l.value());
    return 3;
}

int light_set_color(lua_State* L) {
    ScriptState& s = active(L);
    const size_t i = check_light(L, s);
    check_arg_count(L, 3);
    const glm::vec3 value = check_vec3(L, 2);
    guarded(L, [&] {
        s.begin_staging();
        set_light_color(s.staging, int(i), value);
        s.light_edits[i] |= kPowerEdit;
    });
    return 0;
}

int light_enabled(lua_State* L) {
    const ScriptState& s = active(L);
    const size_t i = check_light(L, s);
    check_arg_count(L, 0);
    lua_pushboolean(L, s.view().lights[i].enabled);
    return 1;
}

int light_set_enabled(lua_State* L) {
    ScriptState& s = active(L);
    const size_t i = check_light(L, s);
    check_arg_count(L, 1);
    luaL_checktype(L, 2, LUA_TBOOLEAN);
    const bool enabled = lua_toboolean(L, 2) != 0;
    guarded(L, [&] {
        s.begin_staging();
        set_light_enabled(s.staging, int(i), enabled);
        s.light_edits[i] |= kEnabledEdit;
    });
    return 0;
}

// ---- the scene ------------------------------------------------------------------------------

// "no object named 'x' (the scene has: a, b, c)"
template <class Items>
int no_such(lua_State* L, const char* kind, const char* name, const Items& items) {
    luaL_Buffer b;
    luaL_buffinit(L, &b);
    for (size_t i = 0; i < items.size(); ++i) {
        if (i > 0) luaL_addstring(&b, ", ");
        luaL_addlstring(&b, items[i].name.data(), items[i].name.size());
    }
    luaL_pushresult(&b);
    return luaL_error(L, "no %s named '%s' (the scene has: %s)", kind, name, lua_tostring(L, -1));
}

int scene_object(lua_State* L) {
    const ScriptState& s = active(L);
    luaL_checkudata(L, 1, kSceneType);
    check_arg_count(L, 1);
    const char* name = luaL_checkstring(L, 2);
    const std::vector<Object>& objects = s.view().objects;
    for (size_t i = 0; i < objects.size(); ++i) {
        if (objects[i].name == name) {
            push_handle(L, kObjectType, int(i));
            return 1;
        }
    }
    return no_such(L, "object", name, objects);
}

int scene_light(lua_State* L) {
    const ScriptState& s = active(L);
    luaL_checkudata(L, 1, kSceneType);
    check_arg_count(L, 1);
    const char* name = luaL_checkstring(L, 2);
    const std::vector<Light>& lights = s.view().lights;
    for (size_t i = 0; i < lights.size(); ++i) {
        if (lights[i].name == name) {
            push_handle(L, kLightType, int(i));
            return 1;
        }
    }
    return no_such(L, "light", name, lights);
}

void set_vec3_field(lua_State* L, const char* field, const glm::vec3& v) {
    lua_createtable(L, 3, 0);
    for (int k = 0; k < 3; ++k) {
        lua_pushnumber(L, v[k]);
        lua_rawseti(L, -2, k + 1);
    }
    lua_setfield(L, -2, field);
}

int scene_camera(lua_State* L) {
    const ScriptState& s = active(L);
    luaL_checkudata(L, 1, kSceneType);
    check_arg_count(L, 0);
    const Camera c = s.view().camera;
    lua_createtable(L, 0, 4);
    set_vec3_field(L, "eye", c.eye);
    set_vec3_field(L, "target", c.target);
    set_vec3_field(L, "up", c.up);
    lua_pushnumber(L, c.fov_y);
    lua_setfield(L, -2, "fov_y");
    return 1;
}

// The value on top of the stack as {x, y, z}.
glm::vec3 camera_vec3(lua_State* L, const char* field) {
    if (lua_type(L, -1) != LUA_TTABLE || lua_rawlen(L, -1) != 3)
        luaL_error(L, "camera field '%s': expected a table of 3 numbers {x, y, z}", field);
    glm::vec3 v{0.0f};
    for (int k = 0; k < 3; ++k) {
        lua_rawgeti(L, -1, k + 1);
        if (lua_type(L, -1) != LUA_TNUMBER || !finite_float(lua_tonumber(L, -1)))
            luaL_error(L, "camera field '%s': element %d is not a finite number", field, k + 1);
        v[k] = float(lua_tonumber(L, -1));
        lua_pop(L, 1);
    }
    return v;
}

int scene_set_camera(lua_State* L) {
    ScriptState& s = active(L);
    luaL_checkudata(L, 1, kSceneType);
    check_arg_count(L, 1);
    luaL_checktype(L, 2, LUA_TTABLE);
    Camera c = s.view().camera;  // fields the table leaves out keep their values
    lua_pushnil(L);
    while (lua_next(L, 2) != 0) {
        const char* key = lua_type(L, -2) == LUA_TSTRING ? lua_tostring(L, -2) : "";
        if (std::strcmp(key, "eye") == 0) {
            c.eye = camera_vec3(L, key);
        } else if (std::strcmp(key, "target") == 0) {
            c.target = camera_vec3(L, key);
        } else if (std::strcmp(key, "up") == 0) {
            c.up = camera_vec3(L, key);
        } else if (std::strcmp(key, "fov_y") == 0) {
            if (lua_type(L, -1) != LUA_TNUMBER || !finite_float(lua_tonumber(L, -1)))
                luaL_error(L, "camera field 'fov_y': expected a number (degrees)");
            c.fov_y = float(lua_tonumber(L, -1));
        } else {
            lua_pushvalue(L, -2);  // tolstring would confuse lua_next if done on the key itself
            luaL_error(L, "unknown camera field '%s' (expected eye, target, up, fov_y)",
                       luaL_tolstring(L, -1, nullptr));
        }
        lua_pop(L, 1);
    }
    guarded(L, [&] {
        s.begin_staging();
        set_camera(s.staging, c);
        s.camera_edited = true;
    });
    return 0;
}

constexpr luaL_Reg kSceneMethods[] = {{"object", scene_object},
                                      {"light", scene_light},
                                      {"camera", scene_camera},
                                      {"set_camera", scene_set_camera},
                                      {nullptr, nullptr}};

constexpr luaL_Reg kObjectMethods[] = {{"name", object_name},
                                       {"position", object_position},
                                       {"set_position", object_set_position},
                                       {"translate", object_translate},
                                       {"rotate", object_rotate},
                                       {"albedo", object_albedo},
                                       {"set_albedo", object_set_albedo},
                                       {"__tostring", handle_tostring},
                                       {"__eq", handle_eq},
                                       {nullptr, nullptr}};

constexpr luaL_Reg kLightMethods[] = {{"name", light_name},
                                      {"position", light_position},
                                      {"set_position", light_set_position},
                                      {"move", light_move},
                                      {"color", light_color},
                                      {"set_color", light_set_color},
                                      {"enabled", light_enabled},
                                      {"set_enabled", light_set_enabled},
                                      {"__tostring", handle_tostring},
                                      {"__eq", handle_eq},
                                      {nullptr, nullptr}};

void register_type(lua_State* L, const char* name, const luaL_Reg* methods) {
    luaL_newmetatable(L, name);
    luaL_setfuncs(L, methods, 0);
    lua_pushvalue(L, -1);
    lua_setfield(L, -2, "__index");
    lua_pushboolean(L, 0);  // getmetatable() sees false: scripts cannot reach the method tables
    lua_setfield(L, -2, "__metatable");
    lua_pop(L, 1);
}

// ---- protected bodies -----------------------------------------------------------------------

int open_sandbox(lua_State* L) {
    const luaL_Reg libs[] = {{LUA_GNAME, luaopen_base},       {LUA_STRLIBNAME, luaopen_string},
                             {LUA_TABLIBNAME, luaopen_table}, {LUA_MATHLIBNAME, luaopen_math},
                             {LUA_UTF8LIBNAME, luaopen_utf8}, {LUA_COLIBNAME, luaopen_coroutine}};
    for (const luaL_Reg& lib : libs) {
        luaL_requiref(L, lib.name, lib.func, 1);
        lua_pop(L, 1);
    }
    lua_pushglobaltable(L);
    for (const char* name : kBlockedGlobals) {
        lua_pushnil(L);
        lua_setfield(L, -2, name);
    }
    lua_getfield(L, -1, LUA_STRLIBNAME);  // bytecode is useless without binary load, which is gone
    lua_pushnil(L);
    lua_setfield(L, -2, "dump");
    // Strings' methods are this table's (their metatable's __index), so s:match is bounded too.
    for (const char* name : {"find", "match", "gmatch", "gsub"}) {
        lua_getfield(L, -1, name);
        lua_pushstring(L, name);
        lua_pushcclosure(L, bounded_pattern, 2);
        lua_setfield(L, -2, name);
    }
    lua_pop(L, 1);
    lua_pushcfunction(L, print_to_stderr);
    lua_setfield(L, -2, "print");
    lua_getfield(L, -1, "setmetatable");
    lua_pushcclosure(L, setmetatable_without_gc, 1);
    lua_setfield(L, -2, "setmetatable");
    // Renders must repeat: math.random starts from a fixed seed, not the clock.
    lua_getfield(L, -1, LUA_MATHLIBNAME);
    lua_getfield(L, -1, "randomseed");
    lua_pushinteger(L, 0);
    lua_call(L, 1, 0);
    lua_pop(L, 1);
    lua_createtable(L, 0, 1);
    lua_pushcfunction(L, blocked_global);
    lua_setfield(L, -2, "__index");
    lua_setmetatable(L, -2);

    register_type(L, kSceneType, kSceneMethods);
    register_type(L, kObjectType, kObjectMethods);
    register_type(L, kLightType, kLightMethods);
    lua_newuserdatauv(L, 0, 0);
    luaL_setmetatable(L, kSceneType);
    lua_pushvalue(L, -1);
    lua_setfield(L, LUA_REGISTRYINDEX, kSceneKey);
    lua_setfield(L, -2, "scene");
    lua_pop(L, 1);
    return 0;
}

struct LoadRequest {
    const std::string* source;
};

int load_chunk(lua_State* L) {
    const auto* request = static_cast<const LoadRequest*>(lua_touserdata(L, 1));
    ScriptState& s = state_of(L);
    // Learn how Lua abbreviates the chunk name, from an empty chunk of the same name.
    luaL_loadbufferx(L, "", 0, s.chunk_name.c_str(), "t");
    lua_Debug ar;
    lua_getinfo(L, ">S", &ar);
    std::memcpy(s.short_src, ar.short_src, sizeof s.short_src);
    // Text only: precompiled chunks can crash the VM.
    if (luaL_loadbufferx(L, request->source->data(), request->source->size(), s.chunk_name.c_str(),
                         "t") != LUA_OK)
        return lua_error(L);
    lua_call(L, 0, 0);
    return 0;
}

struct CallRequest {
    const char* callback;
    bool with_frame;
    lua_Integer frame;
    lua_Number time;
};

int call_callback(lua_State* L) {
    const auto* request = static_cast<const CallRequest*>(lua_touserdata(L, 1));
    const int type = lua_getglobal(L, request->callback);
    if (type == LUA_TNIL) return 0;
    if (type != LUA_TFUNCTION)
        return luaL_error(L, "global '%s' must be a function, not a %s", request->callback,
                          lua_typename(L, type));
    lua_getfield(L, LUA_REGISTRYINDEX, kSceneKey);
    if (request->with_frame) {
        lua_pushinteger(L, request->frame);
        lua_pushnumber(L, request->time);
    }
    lua_call(L, request->with_frame ? 3 : 1, 0);
    return 0;
}

int full_collect(lua_State* L) {
    lua_gc(L, LUA_GCCOLLECT);
    return 0;
}

std::string read_script(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        throw_input_error(path, "", "cannot open script (no such file)");
    if (!std::filesystem::is_regular_file(path, ec))
        throw_input_error(path, "",
                          "a script must be a regular file (this is a directory, "
                          "device or other special file)");
    const auto size = std::filesystem::file_size(path, ec);
    if (ec || size > kMaxScriptBytes)
        throw_input_error(
            path, "",
            "script is larger than the limit of " + std::to_string(kMaxScriptBytes >> 20) + " MiB");
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw_input_error(path, "",
                          std::string("cannot open script (") + std::strerror(errno) + ")");
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw_input_error(path, "", "cannot read script");
    return text.str();
}

}  // namespace

// ---- ScriptState: calls into Lua --------------------------------------------------------------

// Runs `body(payload)` under lua_pcall, the budget and the message handler; returns the error.
std::optional<std::string> ScriptState::protected_run(lua_CFunction body, void* payload) {
    instructions_used = 0;
    last_line = 0;
    memory_refused = false;
    lua_sethook(L, count_hook, LUA_MASKCOUNT, hook_step);
    lua_settop(L, 0);
    lua_pushcfunction(L, message_handler);
    lua_pushcfunction(L, body);
    lua_pushlightuserdata(L, payload);
    const int status = lua_pcall(L, 1, 0, 1);
    std::optional<std::string> error;
    if (status == LUA_ERRMEM) {
        error = memory_message();
    } else if (status != LUA_OK) {
        size_t length = 0;
        const char* text = lua_tolstring(L, -1, &length);
        error = printable(located(text ? std::string(text, length) : std::string("unknown error")));
    }
    lua_settop(L, 0);
    return error;
}

void ScriptState::collect_garbage() {
    lua_settop(L, 0);
    lua_pushcfunction(L, full_collect);
    lua_pcall(L, 0, 0, 0);  // finalizer errors are Lua's to swallow; nothing to report
    lua_settop(L, 0);
}

bool ScriptState::call(Scene& target, const char* callback, bool with_frame, int frame,
                       double time) {
    struct Binding {  // unbinds the scene even if building a message throws
        ScriptState& s;
        ~Binding() {
            s.scene = nullptr;
            s.staged = false;
        }
    } binding{*this};
    scene = &target;
    staged = false;
    CallRequest request{callback, with_frame, lua_Integer(frame), lua_Number(time)};
    std::optional<std::string> error = protected_run(call_callback, &request);
    if (!error && staged) {
        try {
            commit(target);
        } catch (const std::exception& e) {
            error = path + ": applying the script's edits failed: " + e.what();
        }
    }
    // A memory error leaves the failed call's garbage; free it so the next call has room.
    if (error && memory_refused) collect_garbage();
    last_error = error;
    if (error) ++error_count;
    return !error;
}

// ---- Script ---------------------------------------------------------------------------------

Script::Script(const std::string& path, const ScriptLimits& limits)
    : Script(read_script(path), path, limits, FromText{}) {}

Script Script::from_string(const std::string& source, const std::string& chunk_name,
                           const ScriptLimits& limits) {
    return Script(source, chunk_name, limits, FromText{});
}

Script::Script(const std::string& source, const std::string& chunk_name, const ScriptLimits& limits,
               FromText)
    : state_(std::make_unique<ScriptState>()) {
    ScriptState& s = *state_;
    s.path = chunk_name;
    s.chunk_name = "@" + chunk_name;
    s.limits = limits;
    s.hook_step = int(std::clamp<int64_t>(limits.instructions, 1, kHookStep));
    s.L = lua_newstate(allocate, &s);
    if (!s.L)
        throw_input_error(chunk_name, "", "cannot start a Lua interpreter within the memory limit");
    if (auto error = s.protected_run(open_sandbox, nullptr)) throw InputError(*error);
    LoadRequest request{&source};
    if (auto error = s.protected_run(load_chunk, &request)) throw InputError(*error);
}

Script::Script(Script&&) noexcept = default;
Script& Script::operator=(Script&&) noexcept = default;
Script::~Script() = default;

bool Script::on_start(Scene& scene) { return state_->call(scene, "on_start", false, 0, 0.0); }

bool Script::on_frame(Scene& scene, int frame, double time) {
    return state_->call(scene, "on_frame", true, frame, time);
}

const std::optional<std::string>& Script::last_error() const { return state_->last_error; }
int Script::error_count() const { return state_->error_count; }
const std::string& Script::path() const { return state_->path; }

}  // namespace ag
