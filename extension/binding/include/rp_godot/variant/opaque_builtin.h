#pragma once
// Storage and lifetime of the builtins whose memory the engine manages (String, Array, ...).
// Construction, copy and destruction go through the engine's own constructors and destructor,
// looked up once per type. The generated classes add every builtin method on top.

#include <rp_godot/core/internal.h>

#include <cstring>
#include <string>
#include <utility>

namespace godot::internal {

template <typename Derived, size_t Size, GDExtensionVariantType Type>
class OpaqueBuiltin {
public:
	static constexpr GDExtensionVariantType VARIANT_TYPE = Type;

	OpaqueBuiltin() { _constructor(0)(_opaque, nullptr); }
	OpaqueBuiltin(const OpaqueBuiltin &p_other) {
		const GDExtensionConstTypePtr args[] = { p_other._opaque };
		_constructor(1)(_opaque, args);
	}
	// A move takes the other's storage and leaves it default-constructed.
	OpaqueBuiltin(OpaqueBuiltin &&p_other) noexcept {
		std::memcpy(_opaque, p_other._opaque, Size);
		_constructor(0)(p_other._opaque, nullptr);
	}
	~OpaqueBuiltin() { _destroy(); }

	OpaqueBuiltin &operator=(const OpaqueBuiltin &p_other) {
		if (this != &p_other) {
			_destroy();
			const GDExtensionConstTypePtr args[] = { p_other._opaque };
			_constructor(1)(_opaque, args);
		}
		return *this;
	}
	OpaqueBuiltin &operator=(OpaqueBuiltin &&p_other) noexcept {
		if (this != &p_other) {
			uint8_t tmp[Size];
			std::memcpy(tmp, _opaque, Size);
			std::memcpy(_opaque, p_other._opaque, Size);
			std::memcpy(p_other._opaque, tmp, Size);
		}
		return *this;
	}

	GDExtensionTypePtr _native_ptr() { return _opaque; }
	// Releases the content for the engine to construct a new one in place (a to-type conversion).
	GDExtensionUninitializedTypePtr _uninitialized_ptr() {
		_destroy();
		return _opaque;
	}
	GDExtensionConstTypePtr _native_ptr() const { return _opaque; }

protected:
	// Adopts storage that the engine filled (e.g. from a ptrcall), without a constructor.
	struct Uninitialized {};
	explicit OpaqueBuiltin(Uninitialized) {}

	static GDExtensionPtrConstructor _constructor(int32_t p_index) {
		// Index 0 is the default constructor and 1 the copy constructor for every builtin type.
		static const GDExtensionPtrConstructor ctors[2] = { builtin_constructor(Type, 0), builtin_constructor(Type, 1) };
		return p_index < 2 ? ctors[p_index] : builtin_constructor(Type, p_index);
	}
	void _destroy() {
		static const GDExtensionPtrDestructor dtor = builtin_destructor(Type);
		if (dtor) { // RID has none: its storage is a plain id.
			dtor(_opaque);
		}
	}

	alignas(8) uint8_t _opaque[Size];
};

} // namespace godot::internal
