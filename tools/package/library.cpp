// libafterglow.so (tools/package/afterglow.h): the static libraries whole, plus its version.
#include "tools/package/afterglow.h"

namespace ag {

const char* library_version() { return AG_VERSION; }

}  // namespace ag
