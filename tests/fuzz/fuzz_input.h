// Helpers shared by the libFuzzer targets (tests/fuzz, tools/fuzz): a scratch folder per process
// and the one rule every target checks, that bad input ends in an InputError and nothing else.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "shared/input_error.h"

namespace ag::fuzz {

// A folder of this process's own under the system temp folder (removed at exit by the OS's tmp
// cleaning, not here: libFuzzer exits through _exit).
inline const std::filesystem::path& scratch_dir() {
    static const std::filesystem::path dir = [] {
        std::filesystem::path d =
            std::filesystem::temp_directory_path() / ("ag_fuzz_" + std::to_string(getpid()));
        std::filesystem::create_directories(d);
        return d;
    }();
    return dir;
}

inline std::string write_scratch(const std::string& name, const std::string& bytes) {
    const std::filesystem::path p = scratch_dir() / name;
    std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
    return p.string();
}

inline std::string as_string(const uint8_t* data, size_t size) {
    return std::string(reinterpret_cast<const char*>(data), size);
}

// Runs `f`; an InputError is the expected answer to bad input. Any other exception escapes, and
// libFuzzer reports it as a crash (std::terminate).
template <typename F>
void expect_input_errors_only(F&& f) {
    try {
        f();
    } catch (const InputError&) {
    }
}

}  // namespace ag::fuzz
