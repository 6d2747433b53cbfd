"""How each type of the engine's API dump appears in RoomProbe's C++ binding.

For every type the dump names, TypeMapper.resolve gives a TypeInfo that knows its C++
parameter and return types and how a value crosses a ptrcall in each direction. The rules
follow the engine's PtrToArg conventions: integers travel as int64, floats as double, bool as
one byte, objects (and Ref<T>) as a pointer to the object pointer, builtins by address.
"""

import re

# Builtins with engine-managed storage: construction, copy and destruction go through the interface.
OPAQUE_BUILTINS = [
    "String", "StringName", "NodePath", "RID", "Callable", "Signal", "Dictionary", "Array",
    "PackedByteArray", "PackedInt32Array", "PackedInt64Array", "PackedFloat32Array",
    "PackedFloat64Array", "PackedStringArray", "PackedVector2Array", "PackedVector3Array",
    "PackedColorArray", "PackedVector4Array",
]

# Builtins that are plain structs of floats or ints, written by hand in math_types.h.
POD_BUILTINS = [
    "Vector2", "Vector2i", "Rect2", "Rect2i", "Vector3", "Vector3i", "Transform2D", "Vector4",
    "Vector4i", "Plane", "Quaternion", "AABB", "Basis", "Transform3D", "Projection", "Color",
]

INT_META = {
    None: "int64_t", "int8": "int8_t", "int16": "int16_t", "int32": "int32_t", "int64": "int64_t",
    "uint8": "uint8_t", "uint16": "uint16_t", "uint32": "uint32_t", "uint64": "uint64_t",
    "char16": "char16_t", "char32": "char32_t",
}

CPP_KEYWORDS = {
    "and", "or", "not", "xor", "new", "delete", "class", "default", "operator", "template", "this",
    "auto", "bool", "int", "float", "char", "union", "struct", "register", "namespace", "char16_t",
    "char32_t", "enum", "const", "static", "typename", "private", "public", "protected", "virtual",
}


def cpp_name(name):
    return name + "_" if name in CPP_KEYWORDS else name


def snake(name):
    """CamelCase to snake_case the way Godot names its files (Node3D -> node_3d, AABB -> aabb)."""
    s = re.sub(r"([A-Z]+)([A-Z][a-z])", r"\1_\2", name)
    s = re.sub(r"([a-z])([A-Z0-9])", r"\1_\2", s)
    s = re.sub(r"([0-9])([A-Z])", r"\1_\2", s)
    return s.lower().replace("2_d", "2d").replace("3_d", "3d")


def snake_plain(name):
    """CamelCase to snake_case as the C interface names things (PackedVector2Array -> packed_vector2_array)."""
    return re.sub(r"([a-z0-9])([A-Z])", r"\1_\2", name).lower()


class TypeInfo:
    def __init__(self, param, ret, kind, slot=None, zero="{}"):
        self.param = param  # C++ parameter type
        self.ret = ret  # C++ return type
        self.kind = kind
        self.slot = slot  # ptrcall slot type for scalars and objects
        self._zero = zero

    def zero(self):
        return self._zero

    def encode_arg(self, name, tmp):
        """(statement, pointer) passing argument `name` through a ptrcall."""
        if self.kind in ("int", "float", "bool", "enum"):
            return f"{self.slot} {tmp} = static_cast<{self.slot}>({name});", f"&{tmp}"
        if self.kind == "object":
            return f"GDExtensionObjectPtr {tmp} = internal::owner_of({name});", f"&{tmp}"
        if self.kind == "ref":
            return f"GDExtensionObjectPtr {tmp} = internal::owner_of({name}.ptr());", f"&{tmp}"
        return None, f"&{name}"

    def ret_slot_decl(self, var):
        if self.kind in ("int", "float", "bool", "enum"):
            return f"{self.slot} {var} = 0;"
        if self.kind in ("object", "ref"):
            return f"GDExtensionObjectPtr {var} = nullptr;"
        return f"{self.ret} {var};"

    def ret_convert(self, var):
        if self.kind == "bool":
            return f"{var} != 0"
        if self.kind in ("int", "float", "enum"):
            return f"static_cast<{self.ret}>({var})"
        if self.kind == "object":
            return f"internal::wrap<{self.slot_class}>({var})"
        if self.kind == "ref":
            return f"{self.ret}::_adopt(internal::wrap<{self.slot_class}>({var}))"
        return var

    def from_ptr(self, p):
        """The C++ value of a ptrcall argument that the engine passes to RoomProbe."""
        if self.kind == "bool":
            return f"(*static_cast<const GDExtensionBool *>({p}) != 0)"
        if self.kind in ("int", "float", "enum"):
            return f"static_cast<{self.ret}>(*static_cast<const {self.slot} *>({p}))"
        if self.kind == "object":
            return f"internal::wrap<{self.slot_class}>(*static_cast<const GDExtensionObjectPtr *>({p}))"
        if self.kind == "ref":
            return f"{self.ret}(internal::wrap<{self.slot_class}>(internal::gdi.ref_get_object({p})))"
        return f"*static_cast<const {self.ret} *>({p})"

    def to_ptr(self, value, r):
        """A statement that writes `value` into the engine's return slot `r`."""
        if self.kind in ("int", "float", "bool", "enum"):
            return f"*static_cast<{self.slot} *>({r}) = static_cast<{self.slot}>({value});"
        if self.kind == "object":
            return f"*static_cast<GDExtensionObjectPtr *>({r}) = internal::owner_of({value});"
        if self.kind == "ref":
            return f"{{ auto v = {value}; internal::gdi.ref_set_object({r}, internal::owner_of(v.ptr())); }}"
        return f"*static_cast<{self.ret} *>({r}) = {value};"

    def default_literal(self, text):
        """A C++ expression for a default value as the dump writes it, or None."""
        t = text.strip()
        if self.kind == "bool":
            return t if t in ("true", "false") else None
        if self.kind == "int" and re.fullmatch(r"-?\d+", t):
            return t
        if self.kind == "float" and re.fullmatch(r"-?\d+(\.\d*)?(e-?\d+)?", t):
            return t if "." in t or "e" in t else t + ".0"
        if self.kind == "enum" and re.fullmatch(r"-?\d+", t):
            return f"static_cast<{self.ret}>({t})"
        if self.kind in ("object", "ref") and t == "null":
            return "nullptr" if self.kind == "object" else f"{self.ret}()"
        if self.kind == "variant" and t == "null":
            return "Variant()"
        if self.kind == "opaque":
            if t in ('""', '&""', "[]", "{}", "RID()", "Callable()") or t == f"{self.ret}()":
                return f"{self.ret}()"
            if re.fullmatch(r"Array\[\w+\]\(\[\]\)", t):
                return "Array()"
            m = re.fullmatch(r'(&|\^)?"([^"\\]*)"', t)
            if m:
                return f'{self.ret}("{m.group(2)}")'
        if self.kind == "pod":
            m = re.fullmatch(r"(\w+)\(([-0-9., e]*)\)", t)
            if m and m.group(1) == self.ret and self.ret in ("Vector2", "Vector2i", "Vector3", "Vector3i", "Vector4", "Vector4i", "Color", "Rect2", "Rect2i"):
                return t
        return None


class TypeMapper:
    def __init__(self, api):
        self.api = api
        self.known = {}
        self.global_enums = {e["name"] for e in api["global_enums"]}
        self._ancestors = {}

    def set_known_classes(self, classes):
        self.known = classes
        for name in classes:
            chain, c = set(), name
            while c:
                chain.add(c)
                c = classes[c].get("inherits") if c in classes else None
            self._ancestors[name] = chain

    def _resolve(self, t, meta, owner):
        if t == "bool":
            return TypeInfo("bool", "bool", "bool", "GDExtensionBool", "false")
        if t == "int":
            c = INT_META.get(meta, "int64_t")
            return TypeInfo(c, c, "int", "int64_t", "0")
        if t == "float":
            c = "float" if meta == "float" else "double"
            return TypeInfo(c, c, "float", "double", "0")
        if t == "Variant":
            return TypeInfo("const Variant &", "Variant", "variant", zero="Variant()")
        if t in OPAQUE_BUILTINS:
            return TypeInfo(f"const {t} &", t, "opaque", zero=f"{t}()")
        if t in POD_BUILTINS:
            return TypeInfo(f"const {t} &", t, "pod", zero=f"{t}()")
        if t.startswith("typedarray::"):
            return TypeInfo("const Array &", "Array", "opaque", zero="Array()")
        if t.startswith("typeddictionary::"):
            return TypeInfo("const Dictionary &", "Dictionary", "opaque", zero="Dictionary()")
        if t.startswith("bitfield::"):
            return TypeInfo("int64_t", "int64_t", "enum", "int64_t", "0")
        if t.startswith("enum::"):
            full = t[len("enum::"):]
            cpp = "int64_t"
            if "." not in full and full in self.global_enums:
                cpp = full
            elif full == "Variant.Type":
                cpp = "Variant::Type"
            elif "." in full:
                cls = full.split(".")[0]
                # A class's own enums, and its ancestors', are complete where its header is read.
                if owner in self._ancestors and cls in self._ancestors[owner]:
                    cpp = full.replace(".", "::")
            return TypeInfo(cpp, cpp, "enum", "int64_t", f"static_cast<{cpp}>(0)")
        if t in self.known:
            if self.known[t].get("is_refcounted"):
                info = TypeInfo(f"const Ref<{t}> &", f"Ref<{t}>", "ref", zero=f"Ref<{t}>()")
            else:
                info = TypeInfo(f"{t} *", f"{t} *", "object", zero="nullptr")
            info.slot_class = t
            return info
        return None

    def is_supported(self, t, owner):
        return self._resolve(t, None, owner) is not None

    def resolve(self, t, meta, owner):
        info = self._resolve(t, meta, owner)
        if info is None:
            raise KeyError(t)
        return info

    def method_supported(self, m, owner):
        types = [a["type"] for a in m.get("arguments", [])]
        ret = m.get("return_type") or (m.get("return_value") or {}).get("type")
        if ret:
            types.append(ret)
        return all(self.is_supported(t, owner) for t in types)
