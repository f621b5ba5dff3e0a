// Anchor for p2i_msgs until the codec lands.
#include "msgs/wire.h"
