// Scene-edit scripts in Lua 5.4 (the animated scenes of Larsen ch. 14): a sandboxed interpreter
// whose on_start/on_frame callbacks change the scene only through scene_edit.h. The only file that
// includes Lua. The Lua-side API, sandbox and error rules are in docs/scripting.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "shared/scene.h"

namespace ag {

// Per-script limits. A callback that runs out of either fails like any runtime error.
struct ScriptLimits {
    int64_t instructions = 10'000'000;       // Lua VM instructions per callback (≈ tens of ms)
    size_t memory_bytes = size_t(64) << 20;  // the whole interpreter, globals included
};

class ScriptState;  // the interpreter; defined in script.cpp

// One loaded script. The chunk runs once when loaded (to define its callbacks and globals);
// the globals persist between callbacks. Callbacks are all-or-nothing: edits go to a staging copy
// and reach the scene, through scene_edit.h, only when the callback returns without error.
class Script {
public:
    // Loads and runs the file. A missing file, a syntax error or an error in the chunk's own
    // top-level code is an InputError "FILE:LINE: message".
    explicit Script(const std::string& path, const ScriptLimits& limits = {});
    // Same from text; `chunk_name` stands for the file in messages.
    static Script from_string(const std::string& source, const std::string& chunk_name,
                              const ScriptLimits& limits = {});

    Script(Script&&) noexcept;
    Script& operator=(Script&&) noexcept;
    ~Script();

    // Call the script's global on_start(scene) / on_frame(scene, frame, time) if it defines one.
    // Return false if the call failed (runtime error, budget or memory exhausted); the scene is
    // then left exactly as it was and last_error() says why. Never throw for script errors.
    bool on_start(Scene& scene);
    bool on_frame(Scene& scene, int frame, double time);

    // "FILE:LINE: message" of the most recent call, or nullopt if it succeeded.
    const std::optional<std::string>& last_error() const;
    int error_count() const;  // failed calls so far
    const std::string& path() const;

private:
    struct FromText {};
    Script(const std::string& source, const std::string& chunk_name, const ScriptLimits& limits,
           FromText);

    std::unique_ptr<ScriptState> state_;
};

}  // namespace ag
