#pragma once
// Used by generated code: calls with Variant arguments.
#include <rp_godot/core/internal.h>
#include <rp_godot/variant/variant.h>
