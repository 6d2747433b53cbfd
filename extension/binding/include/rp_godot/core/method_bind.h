#pragma once
// Method binds: how the engine calls a RoomProbe method, by ptrcall (typed pointers, from
// compiled code and typed GDScript) and by varcall (Variants, from untyped GDScript and call()).

#include <rp_godot/core/type_info.h>

#include <tuple>
#include <utility>
#include <vector>

namespace godot::internal {

class MethodBindBase {
public:
	virtual ~MethodBindBase() = default;
	virtual GDExtensionClassMethodCall varcall_func() const = 0;
	virtual GDExtensionClassMethodPtrCall ptrcall_func() const = 0;
	virtual bool has_return() const = 0;
	virtual bool is_const() const = 0;
	// Index -1 is the return value.
	virtual GDExtensionVariantType type_of(int p_index) const = 0;
	virtual const char *class_name_of(int p_index) const = 0;
	virtual GDExtensionClassMethodArgumentMetadata metadata_of(int p_index) const = 0;
	virtual bool is_enum(int p_index) const = 0;
	virtual int argument_count() const = 0;

	std::vector<Variant> defaults;

protected:
	// Checks the count and types of a varcall's arguments and fills in the defaults.
	bool prepare_args(const GDExtensionConstVariantPtr *p_args, GDExtensionInt p_count, std::vector<Variant> &r_args, GDExtensionCallError *r_error) const;
};

template <typename T>
using Arg = ArgTraits<std::remove_cv_t<std::remove_reference_t<T>>>;

template <typename T>
constexpr bool is_enum_arg() {
	return std::is_enum_v<std::remove_cv_t<std::remove_reference_t<T>>>;
}

template <typename R, typename... A>
class TypedMethodBind : public MethodBindBase {
public:
	bool has_return() const override { return !std::is_void_v<R>; }
	int argument_count() const override { return sizeof...(A); }
	GDExtensionVariantType type_of(int p_index) const override {
		if (p_index < 0) {
			if constexpr (std::is_void_v<R>) {
				return GDEXTENSION_VARIANT_TYPE_NIL;
			} else {
				return Arg<R>::TYPE;
			}
		}
		constexpr GDExtensionVariantType types[] = { Arg<A>::TYPE..., GDEXTENSION_VARIANT_TYPE_NIL };
		return types[p_index];
	}
	const char *class_name_of(int p_index) const override {
		if (p_index < 0) {
			if constexpr (std::is_void_v<R>) {
				return "";
			} else {
				return Arg<R>::class_name();
			}
		}
		const char *names[] = { Arg<A>::class_name()..., "" };
		return names[p_index];
	}
	GDExtensionClassMethodArgumentMetadata metadata_of(int p_index) const override {
		if (p_index < 0) {
			if constexpr (std::is_void_v<R>) {
				return GDEXTENSION_METHOD_ARGUMENT_METADATA_NONE;
			} else {
				return Arg<R>::META;
			}
		}
		constexpr GDExtensionClassMethodArgumentMetadata metas[] = { Arg<A>::META..., GDEXTENSION_METHOD_ARGUMENT_METADATA_NONE };
		return metas[p_index];
	}
	bool is_enum(int p_index) const override {
		if (p_index < 0) {
			if constexpr (std::is_void_v<R>) {
				return false;
			} else {
				return is_enum_arg<R>();
			}
		}
		constexpr bool enums[] = { is_enum_arg<A>()..., false };
		return enums[p_index];
	}
};

// A member function of an extension class C.
template <typename C, bool Const, typename R, typename... A>
class MemberMethodBind : public TypedMethodBind<R, A...> {
public:
	using Fn = std::conditional_t<Const, R (C::*)(A...) const, R (C::*)(A...)>;
	explicit MemberMethodBind(Fn p_fn) : fn(p_fn) {}
	bool is_const() const override { return Const; }
	GDExtensionClassMethodCall varcall_func() const override { return &varcall; }
	GDExtensionClassMethodPtrCall ptrcall_func() const override { return &ptrcall; }

private:
	Fn fn;

	static C *self(GDExtensionClassInstancePtr p_instance) { return static_cast<C *>(static_cast<Wrapped *>(p_instance)); }

	static void ptrcall(void *p_bind, GDExtensionClassInstancePtr p_instance, const GDExtensionConstTypePtr *p_args, GDExtensionTypePtr r_ret) {
		auto *bind = static_cast<MemberMethodBind *>(p_bind);
		[&]<size_t... I>(std::index_sequence<I...>) {
			if constexpr (std::is_void_v<R>) {
				(self(p_instance)->*(bind->fn))(Arg<A>::from_ptr(p_args[I])...);
			} else {
				Arg<R>::to_ptr((self(p_instance)->*(bind->fn))(Arg<A>::from_ptr(p_args[I])...), r_ret);
			}
		}(std::index_sequence_for<A...>{});
	}

	static void varcall(void *p_bind, GDExtensionClassInstancePtr p_instance, const GDExtensionConstVariantPtr *p_args, GDExtensionInt p_count, GDExtensionVariantPtr r_ret, GDExtensionCallError *r_error) {
		auto *bind = static_cast<MemberMethodBind *>(p_bind);
		std::vector<Variant> args;
		if (!bind->prepare_args(p_args, p_count, args, r_error)) {
			return;
		}
		[&]<size_t... I>(std::index_sequence<I...>) {
			if constexpr (std::is_void_v<R>) {
				(self(p_instance)->*(bind->fn))(Arg<A>::from_variant(args[I])...);
			} else {
				Variant ret = Arg<R>::to_variant((self(p_instance)->*(bind->fn))(Arg<A>::from_variant(args[I])...));
				gdi.variant_new_copy(r_ret, ret._native_ptr());
			}
		}(std::index_sequence_for<A...>{});
	}
};

// A static function, registered as a static method of an extension class.
template <typename R, typename... A>
class StaticMethodBind : public TypedMethodBind<R, A...> {
public:
	explicit StaticMethodBind(R (*p_fn)(A...)) : fn(p_fn) {}
	bool is_const() const override { return false; }
	GDExtensionClassMethodCall varcall_func() const override { return &varcall; }
	GDExtensionClassMethodPtrCall ptrcall_func() const override { return &ptrcall; }

private:
	R (*fn)(A...);

	static void ptrcall(void *p_bind, GDExtensionClassInstancePtr, const GDExtensionConstTypePtr *p_args, GDExtensionTypePtr r_ret) {
		auto *bind = static_cast<StaticMethodBind *>(p_bind);
		[&]<size_t... I>(std::index_sequence<I...>) {
			if constexpr (std::is_void_v<R>) {
				bind->fn(Arg<A>::from_ptr(p_args[I])...);
			} else {
				Arg<R>::to_ptr(bind->fn(Arg<A>::from_ptr(p_args[I])...), r_ret);
			}
		}(std::index_sequence_for<A...>{});
	}

	static void varcall(void *p_bind, GDExtensionClassInstancePtr, const GDExtensionConstVariantPtr *p_args, GDExtensionInt p_count, GDExtensionVariantPtr r_ret, GDExtensionCallError *r_error) {
		auto *bind = static_cast<StaticMethodBind *>(p_bind);
		std::vector<Variant> args;
		if (!bind->prepare_args(p_args, p_count, args, r_error)) {
			return;
		}
		[&]<size_t... I>(std::index_sequence<I...>) {
			if constexpr (std::is_void_v<R>) {
				bind->fn(Arg<A>::from_variant(args[I])...);
			} else {
				Variant ret = Arg<R>::to_variant(bind->fn(Arg<A>::from_variant(args[I])...));
				gdi.variant_new_copy(r_ret, ret._native_ptr());
			}
		}(std::index_sequence_for<A...>{});
	}
};

template <typename M>
struct MethodBindFor;
template <typename C, typename R, typename... A>
struct MethodBindFor<R (C::*)(A...)> {
	using type = MemberMethodBind<C, false, R, A...>;
};
template <typename C, typename R, typename... A>
struct MethodBindFor<R (C::*)(A...) const> {
	using type = MemberMethodBind<C, true, R, A...>;
};

template <typename M>
struct MethodBindClass;
template <typename C, typename R, typename... A>
struct MethodBindClass<R (C::*)(A...)> {
	static const char *name() { return C::get_class_static(); }
};
template <typename C, typename R, typename... A>
struct MethodBindClass<R (C::*)(A...) const> {
	static const char *name() { return C::get_class_static(); }
};

} // namespace godot::internal
