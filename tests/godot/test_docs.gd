extends RoomProbeTestCase
## The class reference, extension/godot/doc_classes/<Class>.xml, must describe exactly what the
## extension registers. The build embeds these files in the library and the editor's help shows
## them; these tests keep them from drifting away from ClassDB.
##
## Like Godot's doctool, the reference lists under <methods> only the methods that are not the
## setter or getter of a property (those are the setter= and getter= of a <member>), and leaves
## out methods whose names start with "_" unless they are virtual.

## The classes RoomProbe registers. Any other class that extension/godot/register_types.cpp
## registers must be documented too. (ClassDB cannot tell RoomProbe's classes from those of the
## test-only binding extension in tests/binding/, which need no reference.)
const CLASSES: Array[StringName] = [&"RigCapture", &"DenseSLAM", &"CoarseRoomModel", &"RoomProbe", &"SurfaceAnchor", &"PRTTransfer"]
const REGISTER_TYPES := "extension/godot/register_types.cpp"

## Tags whose text is code: references inside them are not links.
const CODE_TAGS := ["codeblock", "code"]
## What the editor's loader (DocTools) accepts inside each element; it rejects a whole class
## file at the first tag it does not expect ("Invalid tag in doc file"). Text-only elements map
## to []. <member> and <constant> hold their description as text, not in <description>.
const CHILDREN := {
	"": ["class"],
	"class": ["brief_description", "description", "tutorials", "constructors", "methods", "operators", "signals", "annotations", "members", "theme_items", "constants"],
	"tutorials": ["link"],
	"methods": ["method"],
	"signals": ["signal"],
	"members": ["member"],
	"constants": ["constant"],
	"method": ["return", "returns_error", "param", "description"],
	"signal": ["param", "description"],
}
## Formatting tags that must be closed.
const PAIRED_TAGS := ["b", "i", "u", "s", "code", "codeblock", "kbd", "center", "url"]

var _docs := {}  # class name -> the parsed file (see _parse_doc), filled once
var _ref := RegEx.create_from_string("\\[(member|method|signal|constant|enum|param|annotation|constructor|operator|theme_item) ([^\\]\\s]+)\\]")
var _class_ref := RegEx.create_from_string("\\[([A-Z@][A-Za-z0-9_]*)\\]")


static func doc_dir() -> String:
	return repo_path("extension/godot/doc_classes")


func before_each() -> void:
	if _docs.is_empty():
		for c in _documented_classes():
			_docs[c] = _parse_doc(doc_dir().path_join(c + ".xml"))


# --- tests ----------------------------------------------------------------------------------


func test_doc_folder_has_one_file_per_registered_class() -> void:
	if not assert_true(DirAccess.dir_exists_absolute(doc_dir()), "the doc folder %s exists" % doc_dir()):
		return
	var files := Array(DirAccess.get_files_at(doc_dir())).filter(func(f: String) -> bool: return f.get_extension() == "xml")
	var expected := _documented_classes().map(func(c: String) -> String: return c + ".xml")
	files.sort()
	expected.sort()
	assert_eq(files, expected, "XML files in %s against the classes the extension registers" % doc_dir())
	for c in _documented_classes():
		assert_true(ClassDB.class_exists(c), "%s is registered (the extension is loaded)" % c)
		assert_eq(ClassDB.class_get_api_type(c), ClassDB.API_EXTENSION, "%s comes from an extension" % c)
	assert_true(FileAccess.get_file_as_string(repo_path(REGISTER_TYPES)).contains("register_class"), "%s is readable" % REGISTER_TYPES)


func test_files_parse_and_name_their_class() -> void:
	for c in _documented_classes():
		var doc: Dictionary = _docs[c]
		assert_eq(doc.errors, [], "%s.xml parses" % c)
		assert_eq(doc.name, c, "%s.xml: <class name>" % c)
		assert_eq(doc.inherits, String(ClassDB.get_parent_class(c)), "%s.xml: <class inherits>" % c)


func test_class_descriptions_are_written() -> void:
	for c in _documented_classes():
		var doc: Dictionary = _docs[c]
		assert_true(doc.brief.strip_edges() != "", "%s: <brief_description> is empty" % c)
		assert_true(doc.description.strip_edges() != "", "%s: <description> is empty" % c)
		assert_true(doc.description.contains("[codeblock"), "%s: <description> has a usage example ([codeblock])" % c)


func test_methods_match_class_db() -> void:
	for c in _documented_classes():
		var doc: Dictionary = _docs[c]
		var registered := _registered_methods(c)
		_assert_same_names(c, "method", registered.keys(), doc.methods.keys())
		for m in registered:
			if not doc.methods.has(m):
				continue
			var info: Dictionary = registered[m]
			var entry: Dictionary = doc.methods[m]
			var where := "%s.%s()" % [c, m]
			assert_eq(entry.return_type, _type_name(info["return"], true), "%s: <return type>" % where)
			assert_eq(entry.return_enum, _enum_name(info["return"]), "%s: <return enum>" % where)
			assert_eq(entry.params.map(func(p: Dictionary) -> String: return p.enum_name), info.args.map(_enum_name), "%s: parameter enums" % where)
			assert_eq(entry.params.map(func(p: Dictionary) -> String: return p.name), info.args.map(func(a: Dictionary) -> String: return a.name), "%s: parameter names" % where)
			assert_eq(entry.params.map(func(p: Dictionary) -> String: return p.type), info.args.map(func(a: Dictionary) -> String: return _type_name(a, false)), "%s: parameter types" % where)
			assert_true(entry.description.strip_edges() != "", "%s: description is empty" % where)


func test_members_match_class_db() -> void:
	for c in _documented_classes():
		var doc: Dictionary = _docs[c]
		var registered := _registered_properties(c)
		_assert_same_names(c, "member", registered.keys(), doc.members.keys())
		for p in registered:
			if not doc.members.has(p):
				continue
			var entry: Dictionary = doc.members[p]
			var where := "%s.%s" % [c, p]
			assert_eq(entry.type, _type_name(registered[p], false), "%s: type" % where)
			# As in the doctool, a member's enum is the one its getter returns.
			var getter := ClassDB.class_get_property_getter(c, p)
			var getter_info: Array = ClassDB.class_get_method_list(c, true).filter(func(m: Dictionary) -> bool: return m.name == getter)
			var expected_enum := _enum_name(getter_info[0]["return"]) if getter_info.size() == 1 else ""
			assert_eq(entry.enum_name, expected_enum, "%s: enum" % where)
			assert_eq(entry.setter, String(ClassDB.class_get_property_setter(c, p)), "%s: setter" % where)
			assert_eq(entry.getter, String(ClassDB.class_get_property_getter(c, p)), "%s: getter" % where)
			assert_eq(entry.default, var_to_str(ClassDB.class_get_property_default_value(c, p)), "%s: default" % where)
			assert_true(entry.description.strip_edges() != "", "%s: description is empty" % where)


func test_signals_match_class_db() -> void:
	for c in _documented_classes():
		var doc: Dictionary = _docs[c]
		var registered := {}
		for s in ClassDB.class_get_signal_list(c, true):
			registered[s.name] = s
		_assert_same_names(c, "signal", registered.keys(), doc.signals.keys())
		for s in registered:
			if not doc.signals.has(s):
				continue
			var entry: Dictionary = doc.signals[s]
			var args: Array = registered[s].args
			var where := "%s signal %s" % [c, s]
			assert_eq(entry.params.map(func(p: Dictionary) -> String: return p.name), args.map(func(a: Dictionary) -> String: return a.name), "%s: parameter names" % where)
			assert_eq(entry.params.map(func(p: Dictionary) -> String: return p.type), args.map(func(a: Dictionary) -> String: return _type_name(a, false)), "%s: parameter types" % where)
			assert_eq(entry.params.map(func(p: Dictionary) -> String: return p.enum_name), args.map(_enum_name), "%s: parameter enums" % where)
			assert_true(entry.description.strip_edges() != "", "%s: description is empty" % where)


func test_constants_match_class_db() -> void:
	for c in _documented_classes():
		var doc: Dictionary = _docs[c]
		var registered := Array(ClassDB.class_get_integer_constant_list(c, true))
		_assert_same_names(c, "constant", registered, doc.constants.keys())
		for k in registered:
			if not doc.constants.has(k):
				continue
			var entry: Dictionary = doc.constants[k]
			var where := "%s.%s" % [c, k]
			assert_eq(entry.value, str(ClassDB.class_get_integer_constant(c, k)), "%s: value" % where)
			assert_eq(entry.enum_name, String(ClassDB.class_get_integer_constant_enum(c, k, true)), "%s: enum" % where)
			assert_true(entry.description.strip_edges() != "", "%s: description is empty" % where)


## [member x], [method x], [signal x], [constant x], [enum x] and [ClassName] must name things
## that exist, and [param x] a parameter of the method or signal being described.
func test_cross_references_resolve() -> void:
	for c in _documented_classes():
		var doc: Dictionary = _docs[c]
		for text in _texts(doc):
			for problem in _reference_problems(c, text.text, text.params):
				fail("%s (%s): %s" % [c, text.where, problem])
	assert_true(true)


func test_bbcode_tags_are_closed() -> void:
	for c in _documented_classes():
		var doc: Dictionary = _docs[c]
		for text in _texts(doc):
			for tag in PAIRED_TAGS:
				var opened: int = _count_tag(text.text, tag)
				var closed: int = text.text.count("[/%s]" % tag)
				assert_eq(closed, opened, "%s (%s): [%s] opened %d times, closed %d times" % [c, text.where, tag, opened, closed])


# --- ClassDB's side ----------------------------------------------------------------------------


## The classes that need a doc file: CLASSES and whatever else register_types.cpp registers.
func _documented_classes() -> Array:
	var out := CLASSES.map(func(c: StringName) -> String: return String(c))
	var source := FileAccess.get_file_as_string(repo_path(REGISTER_TYPES))
	var registration := RegEx.create_from_string("register_(?:abstract_|internal_|runtime_|virtual_)?class\\s*<\\s*(?:\\w+\\s*::\\s*)*(\\w+)\\s*>")
	for m in registration.search_all(source):
		if not out.has(m.get_string(1)):
			out.append(m.get_string(1))
	return out


## Methods that belong under <methods>, by name, with their ClassDB info.
func _registered_methods(c: String) -> Dictionary:
	var accessors := {}
	for p in ClassDB.class_get_property_list(c, true):
		accessors[String(ClassDB.class_get_property_setter(c, p.name))] = true
		accessors[String(ClassDB.class_get_property_getter(c, p.name))] = true
	var out := {}
	for m in ClassDB.class_get_method_list(c, true):
		var name: String = m.name
		if name.is_empty() or name.begins_with("_") and not (m.flags & METHOD_FLAG_VIRTUAL):
			continue
		# As in the doctool: only plain accessors are left to <member>; a setter or getter that
		# takes an extra argument (set_param(which, value)) is a method of its own.
		var plain_accessor: bool = m.args.is_empty() or m.args.size() == 1 and m["return"].type == TYPE_NIL
		if accessors.has(name) and plain_accessor:
			continue
		out[name] = m
	return out


## Issue #37: documented ranges drifted from the registered ones (texel_size's inspector offered
## 0.005..0.1 while the text and the setter said 0.001..1). A member whose text states "Values
## outside A to B" must have a range hint of exactly [A, B], and a ranged number's text must say
## what happens outside its range.
func test_documented_ranges_match_the_registered_hints() -> void:
	var stated := RegEx.create_from_string("[Vv]alues outside (-?[0-9.e+]+) to (-?[0-9.e+]+)")
	var checked := 0
	for c in _documented_classes():
		var doc: Dictionary = _docs[c]
		var registered := _registered_properties(c)
		for p in registered:
			if not doc.members.has(p):
				continue
			var where := "%s.%s" % [c, p]
			var info: Dictionary = registered[p]
			var text: String = doc.members[p].description
			var m := stated.search(text)
			if info.hint != PROPERTY_HINT_RANGE or not (info.type in [TYPE_INT, TYPE_FLOAT]):
				continue  # a list to pick from (RoomProbe.resolution's sizes) while the setter takes a range
			var hint := String(info.hint_string).split(",")
			if not assert_true(m != null, "%s: a ranged number whose text does not say \"Values outside A to B\" (hint %s)" % [where, info.hint_string]):
				continue
			assert_eq(float(m.get_string(1)), float(hint[0]), "%s: the documented low end against the hint %s" % [where, info.hint_string])
			assert_eq(float(m.get_string(2)), float(hint[1]), "%s: the documented high end against the hint %s" % [where, info.hint_string])
			checked += 1
	assert_true(checked >= 10, "%d ranged members checked" % checked)


## Properties that belong under <members>, by name: not groups, categories or internal ones.
func _registered_properties(c: String) -> Dictionary:
	var skip := PROPERTY_USAGE_GROUP | PROPERTY_USAGE_SUBGROUP | PROPERTY_USAGE_CATEGORY | PROPERTY_USAGE_INTERNAL
	var out := {}
	for p in ClassDB.class_get_property_list(c, true):
		if p.usage & skip or p.type == TYPE_NIL and p.usage & PROPERTY_USAGE_ARRAY:
			continue
		out[p.name] = p
	return out


## The type name the reference uses: "void" or "Variant" for nothing, the class for objects,
## otherwise the Variant type ("int" for enums, whose name goes into enum=).
static func _type_name(info: Dictionary, is_return: bool) -> String:
	if info.type == TYPE_NIL:
		return "Variant" if info.usage & PROPERTY_USAGE_NIL_IS_VARIANT or not is_return else "void"
	if info.type == TYPE_OBJECT and String(info["class_name"]) != "":
		return String(info["class_name"])
	return type_string(info.type)


## The enum= the reference gives a value: "Class.Enum" when ClassDB marks the value as an enum.
static func _enum_name(info: Dictionary) -> String:
	return String(info["class_name"]) if info.usage & PROPERTY_USAGE_CLASS_IS_ENUM else ""


func _assert_same_names(c: String, kind: String, registered: Array, documented: Array) -> void:
	for n in registered:
		assert_true(documented.has(n), "%s: %s '%s' is registered but not documented in %s.xml" % [c, kind, n, c])
	for n in documented:
		assert_true(registered.has(n), "%s: %s '%s' is documented in %s.xml but not registered" % [c, kind, n, c])


# --- references ------------------------------------------------------------------------------


func _reference_problems(c: String, text: String, params: Array) -> Array[String]:
	var problems: Array[String] = []
	var prose := _without_code(text)
	for m in _ref.search_all(prose):
		var kind := m.get_string(1)
		var target := m.get_string(2)
		if kind == "param":
			if not params.has(target):
				problems.append("[param %s]: not a parameter here (parameters: %s)" % [target, params])
			continue
		var owner := c
		var name := target
		if target.contains("."):
			owner = target.get_slice(".", 0)
			name = target.substr(owner.length() + 1)
		if not ClassDB.class_exists(owner):
			problems.append("[%s %s]: no class '%s'" % [kind, target, owner])
			continue
		if not _class_has(owner, kind, name):
			problems.append("[%s %s]: %s has no %s '%s'" % [kind, target, owner, kind, name])
	for m in _class_ref.search_all(prose):
		var name := m.get_string(1)
		if not (ClassDB.class_exists(name) or _is_builtin_type(name)):
			problems.append("[%s]: no such class or type" % name)
	return problems


static func _class_has(owner: String, kind: String, name: String) -> bool:
	match kind:
		"member":
			return ClassDB.class_get_property_list(owner).any(func(p: Dictionary) -> bool: return p.name == name)
		"method":
			return ClassDB.class_has_method(owner, name)
		"signal":
			return ClassDB.class_has_signal(owner, name)
		"constant":
			return ClassDB.class_has_integer_constant(owner, name)
		"enum":
			return ClassDB.class_has_enum(owner, name)
	return false


static func _is_builtin_type(name: String) -> bool:
	for t in TYPE_MAX:
		if type_string(t) == name:
			return true
	return name == "@GlobalScope" or name == "@GDScript"


## text with the contents of [code] and [codeblock] removed: references there are not links.
static func _without_code(text: String) -> String:
	var out := text
	for tag in CODE_TAGS:
		var re := RegEx.create_from_string("(?s)\\[%s[^\\]]*\\].*?\\[/%s\\]" % [tag, tag])
		out = re.sub(out, "", true)
	return out


static func _count_tag(text: String, tag: String) -> int:
	return RegEx.create_from_string("\\[%s(?:[ =][^\\]]*)?\\]" % tag).search_all(text).size()


## Every description of a parsed file, with where it is and the parameter names [param] may use.
static func _texts(doc: Dictionary) -> Array[Dictionary]:
	var out: Array[Dictionary] = []
	out.append({ where = "brief_description", text = doc.brief, params = [] })
	out.append({ where = "description", text = doc.description, params = [] })
	for group in ["methods", "signals"]:
		for n in doc[group]:
			var entry: Dictionary = doc[group][n]
			var params: Array = entry.params.map(func(p: Dictionary) -> String: return p.name)
			out.append({ where = "%s %s" % [group.trim_suffix("s"), n], text = entry.description, params = params })
	for group in ["members", "constants"]:
		for n in doc[group]:
			out.append({ where = "%s %s" % [group.trim_suffix("s"), n], text = doc[group][n].description, params = [] })
	return out


# --- the XML side ------------------------------------------------------------------------------


## Reads one class reference file into
## { name, inherits, brief, description, errors: Array[String],
##   methods: { name: { return_type, return_enum, params: [{ name, type, enum_name }], description } },
##   members: { name: { type, enum_name, setter, getter, default, description } },
##   signals: { name: { params: [{ name, type, enum_name }], description } },
##   constants: { name: { value, enum_name, description } } }.
static func _parse_doc(path: String) -> Dictionary:
	var doc := {
		name = "", inherits = "", brief = "", description = "", errors = [],
		methods = {}, members = {}, signals = {}, constants = {},
	}
	if not FileAccess.file_exists(path):
		doc.errors.append("%s does not exist" % path)
		return doc
	var parser := XMLParser.new()
	var err := parser.open(path)
	if err != OK:
		doc.errors.append("cannot open %s: %s" % [path, error_string(err)])
		return doc
	var stack: Array[String] = []
	var entry := {}  # the <method>, <member>, <signal> or <constant> being read
	while true:
		err = parser.read()
		if err == ERR_FILE_EOF:
			break
		if err != OK:
			doc.errors.append("XML error %s near byte %d" % [error_string(err), parser.get_node_offset()])
			break
		match parser.get_node_type():
			XMLParser.NODE_ELEMENT:
				var tag := parser.get_node_name()
				var attrs := {}
				for i in parser.get_attribute_count():
					attrs[parser.get_attribute_name(i)] = parser.get_attribute_value(i)
				var parent: String = stack.back() if not stack.is_empty() else ""
				if not CHILDREN.get(parent, []).has(tag):
					doc.errors.append("<%s> inside <%s> near byte %d: the editor rejects the file there" % [tag, parent if parent else "(top)", parser.get_node_offset()])
				match [parent, tag]:
					["", "class"]:
						doc.name = attrs.get("name", "")
						doc.inherits = attrs.get("inherits", "")
					["methods", "method"], ["signals", "signal"]:
						entry = { return_type = "void", return_enum = "", params = [], description = "" }
						_add_entry(doc, parent, attrs.get("name", ""), entry)
					["members", "member"]:
						entry = { type = attrs.get("type", ""), enum_name = attrs.get("enum", ""), setter = attrs.get("setter", ""), getter = attrs.get("getter", ""), default = attrs.get("default", ""), description = "" }
						_add_entry(doc, parent, attrs.get("name", ""), entry)
					["constants", "constant"]:
						entry = { value = attrs.get("value", ""), enum_name = attrs.get("enum", ""), description = "" }
						_add_entry(doc, parent, attrs.get("name", ""), entry)
					["method", "return"]:
						entry.return_type = attrs.get("type", "")
						entry.return_enum = attrs.get("enum", "")
					["method", "param"], ["signal", "param"]:
						entry.params.append({ name = attrs.get("name", ""), type = attrs.get("type", ""), enum_name = attrs.get("enum", "") })
				if not parser.is_empty():
					stack.append(tag)
			XMLParser.NODE_ELEMENT_END:
				if stack.is_empty() or stack.back() != parser.get_node_name():
					doc.errors.append("unexpected </%s> near byte %d" % [parser.get_node_name(), parser.get_node_offset()])
					break
				stack.pop_back()
			XMLParser.NODE_TEXT, XMLParser.NODE_CDATA:
				var text := parser.get_node_data()
				var at: String = stack.back() if not stack.is_empty() else ""
				var parent: String = stack[stack.size() - 2] if stack.size() >= 2 else ""
				match [parent, at]:
					["class", "brief_description"]:
						doc.brief += text
					["class", "description"]:
						doc.description += text
					["method", "description"], ["signal", "description"], ["members", "member"], ["constants", "constant"]:
						entry.description += text
	if stack.size() > 0:
		doc.errors.append("unclosed elements at the end: %s" % [stack])
	return doc


static func _add_entry(doc: Dictionary, group: String, name: String, entry: Dictionary) -> void:
	if name.is_empty():
		doc.errors.append("a <%s> without a name" % group.trim_suffix("s"))
	elif doc[group].has(name):
		doc.errors.append("%s '%s' is documented twice" % [group.trim_suffix("s"), name])
	doc[group][name] = entry
