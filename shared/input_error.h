// Errors in user input (scene files, meshes, scripts, flags): the message names the file, the
// place (JSON path or line) and what was expected. Programmer errors assert instead.
#pragma once

#include <stdexcept>
#include <string>

namespace ag {

class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// "FILE: PLACE: MESSAGE" (PLACE omitted when empty).
[[noreturn]] void throw_input_error(const std::string& file, const std::string& place,
                                    const std::string& message);

// Non-fatal problems (e.g. degenerate triangles dropped) go to stderr through here so that tests
// can capture them.
void warn(const std::string& message);

}  // namespace ag
