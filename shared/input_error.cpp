#include "shared/input_error.h"

#include <iostream>

namespace ag {

void throw_input_error(const std::string& file, const std::string& place,
                       const std::string& message) {
    std::string text = file;
    if (!place.empty()) text += ": " + place;
    text += ": " + message;
    throw InputError(text);
}

void warn(const std::string& message) { std::cerr << "afterglow: warning: " << message << "\n"; }

}  // namespace ag
