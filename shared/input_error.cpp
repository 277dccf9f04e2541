#include "shared/input_error.h"

#include <iostream>

namespace ag {

void throw_input_error(const std::string& file, const std::string& place,
                       const std::string& message) {
    std::string text = file;
    if (!place.empty()) text += ": " + place;
    text += ": " + message;
    // Messages quote what a file held (a PLY keyword, an OBJ index) and reach terminals and logs:
    // control characters other than newline and tab (an escape sequence in a fuzzed mesh) are
    // shown as '?'.
    for (char& c : text)
        if ((static_cast<unsigned char>(c) < 0x20 && c != '\n' && c != '\t') || c == 0x7f) c = '?';
    throw InputError(text);
}

void warn(const std::string& message) { std::cerr << "afterglow: warning: " << message << "\n"; }

}  // namespace ag
