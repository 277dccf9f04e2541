// Settings to and from JSON (the scene file's "settings" block, docs/scene-format.md), walking
// visit_settings() so that the keys, ranges and enum names live in settings.h only.
// Kept out of settings.h and scene.h so that only the parsers see nlohmann.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "shared/settings.h"

namespace ag {

// Overwrites the fields present in `json` (an object of sections plus the top-level "seed" and
// "threads"); absent fields keep their current value. Unknown keys, wrong types, non-finite
// numbers, values outside a field's range and unknown enum names throw InputError naming `file`,
// the JSON path (`path` + "/section/key", e.g. "/settings/photons/groups") and what was expected.
void read_settings(const nlohmann::json& json, Settings& settings, const std::string& file,
                   const std::string& path);

// The settings as a JSON object of the same shape read_settings() accepts (enums as names).
nlohmann::json settings_to_json_value(const Settings& settings);

}  // namespace ag
