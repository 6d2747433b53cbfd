#pragma once
// Ref<T>: a counted reference to a RefCounted engine object, as in Godot's C++.

#include <rp_godot/core/wrapped.h>

namespace godot {

namespace internal {
bool refcounted_init_ref(GDExtensionObjectPtr p_object);
bool refcounted_reference(GDExtensionObjectPtr p_object);
// True when that was the last reference and the object was freed.
bool refcounted_unreference(GDExtensionObjectPtr p_object);
} // namespace internal

template <typename T>
class Ref {
public:
	Ref() = default;
	Ref(T *p_object) { _take(p_object, internal::owner_of(p_object), true); }
	Ref(const Ref &p_other) { _take(p_other._object, p_other._owner, false); }
	template <typename U>
	Ref(const Ref<U> &p_other) {
		T *object = dynamic_cast<T *>(p_other.ptr());
		_take(object, internal::owner_of(object), false);
	}
	Ref(Ref &&p_other) noexcept : _object(p_other._object), _owner(p_other._owner) {
		p_other._object = nullptr;
		p_other._owner = nullptr;
	}
	Ref(const Variant &p_variant) {
		T *object = dynamic_cast<T *>(p_variant.get_object());
		_take(object, internal::owner_of(object), false);
	}
	~Ref() { unref(); }

	Ref &operator=(const Ref &p_other) {
		if (_object != p_other._object) {
			unref();
			_take(p_other._object, p_other._owner, false);
		}
		return *this;
	}
	Ref &operator=(Ref &&p_other) noexcept {
		if (this != &p_other) {
			unref();
			_object = p_other._object;
			_owner = p_other._owner;
			p_other._object = nullptr;
			p_other._owner = nullptr;
		}
		return *this;
	}

	T *ptr() const { return _object; }
	T *operator->() const { return _object; }
	T &operator*() const { return *_object; }
	bool is_valid() const { return _object != nullptr; }
	bool is_null() const { return _object == nullptr; }
	bool operator==(const Ref &p_other) const { return _object == p_other._object; }
	explicit operator bool() const { return _object != nullptr; }

	void instantiate() { *this = Ref(memnew(T)); }
	void unref() {
		if (_owner) {
			internal::refcounted_unreference(_owner);
			_object = nullptr;
			_owner = nullptr;
		}
	}

	// Takes over a reference that the engine already counted (a ptrcall's return value).
	static Ref _adopt(T *p_object) {
		Ref r;
		r._object = p_object;
		r._owner = internal::owner_of(p_object);
		return r;
	}

private:
	// The owner is kept beside the object so that a Ref of an incomplete T can still be
	// copied and released (generated headers only forward-declare most classes).
	void _take(T *p_object, GDExtensionObjectPtr p_owner, bool p_from_raw) {
		if (!p_owner) {
			return;
		}
		// A fresh RefCounted holds one initial count that the first Ref takes over.
		bool ok = p_from_raw ? internal::refcounted_init_ref(p_owner) : internal::refcounted_reference(p_owner);
		if (ok) {
			_object = p_object;
			_owner = p_owner;
		}
	}

	T *_object = nullptr;
	GDExtensionObjectPtr _owner = nullptr;
};

} // namespace godot
