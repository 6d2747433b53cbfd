#include "slam_types.h"

namespace roomprobe {

const char *tracking_state_name(TrackingState p_state) {
	switch (p_state) {
		case TrackingState::Good:
			return "good";
		case TrackingState::Poor:
			return "poor";
		case TrackingState::Lost:
			return "lost";
	}
	return "?";
}

} // namespace roomprobe
