// Anchor for p2i_runtime until the runtime lands.
#include "msgs/wire.h"
