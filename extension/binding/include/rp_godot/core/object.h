#pragma once
// Object, RefCounted and Ref<T>, with Object::cast_to.

#include <rp_godot/core/ref.h>
#include <rp_godot/gen/classes/object.gen.h>
#include <rp_godot/gen/classes/ref_counted.gen.h>

namespace godot {

// cast_to<T>(object): the object as a T, or null when it is none.
template <typename T>
T *cast_to(Wrapped *p_object) {
	return dynamic_cast<T *>(p_object);
}
template <typename T>
const T *cast_to(const Wrapped *p_object) {
	return dynamic_cast<const T *>(p_object);
}

} // namespace godot
