// Anchor for the p2i_model library (the interface in view_synthesizer.h is header-only).
#include "model/view_synthesizer.h"
