#include "yaml_fields.h"

#include <charconv>
#include <cmath>
#include <set>

namespace roomprobe {

bool YamlFieldReader::fail(const std::string &p_field, const std::string &p_problem) {
	error = p_field + ": " + p_problem;
	return false;
}

bool YamlFieldReader::check_keys(const cv::FileNode &p_map, const std::string &p_prefix,
		std::initializer_list<const char *> p_allowed, std::initializer_list<const char *> p_required) {
	std::set<std::string> seen;
	for (cv::FileNodeIterator it = p_map.begin(); it != p_map.end(); ++it) {
		const std::string key = (*it).name();
		bool known = false;
		for (const char *allowed : p_allowed) {
			known = known || key == allowed;
		}
		if (!known) {
			return fail(p_prefix + key, "unknown field");
		}
		if (!seen.insert(key).second) {
			return fail(p_prefix + key, "given twice");
		}
	}
	for (const char *key : p_required) {
		if (!seen.count(key)) {
			return fail(p_prefix + key, "missing");
		}
	}
	return true;
}

bool YamlFieldReader::present(const cv::FileNode &p_node, const std::string &p_field) {
	if (p_node.empty() || p_node.isNone()) {
		return fail(p_field, "missing");
	}
	return true;
}

template <typename T>
bool YamlFieldReader::typed(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key,
		bool (cv::FileNode::*p_is)() const, const char *p_problem, T *r_value) {
	const cv::FileNode node = p_parent[p_key];
	if (!present(node, p_prefix + p_key)) {
		return false;
	}
	if (!(node.*p_is)()) {
		return fail(p_prefix + p_key, p_problem);
	}
	*r_value = static_cast<T>(node);
	return true;
}

bool YamlFieldReader::map(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, cv::FileNode *r_map) {
	return typed(p_parent, p_prefix, p_key, &cv::FileNode::isMap, "must be a map of fields", r_map);
}

bool YamlFieldReader::integer(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, int *r_value) {
	return typed(p_parent, p_prefix, p_key, &cv::FileNode::isInt, "must be an integer", r_value);
}

bool YamlFieldReader::text(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, std::string *r_value) {
	return typed(p_parent, p_prefix, p_key, &cv::FileNode::isString, "must be a string", r_value);
}

bool YamlFieldReader::number(const cv::FileNode &p_node, const std::string &p_field, double *r_value) {
	if (!present(p_node, p_field)) {
		return false;
	}
	if (!p_node.isInt() && !p_node.isReal()) {
		return fail(p_field, "must be a number");
	}
	const double value = static_cast<double>(p_node);
	if (non_finite == NonFinite::Refuse && !std::isfinite(value)) {
		// std::to_chars writes "inf", "-inf", "nan" or "-nan", whatever the format asked for.
		char buffer[16];
		const std::to_chars_result written = std::to_chars(buffer, buffer + sizeof(buffer), value);
		return fail(p_field, "must be finite (got " + std::string(buffer, written.ptr) + ")");
	}
	*r_value = value;
	return true;
}

bool YamlFieldReader::numbers(const cv::FileNode &p_node, const std::string &p_field, size_t p_count, double *r_values) {
	if (!present(p_node, p_field)) {
		return false;
	}
	if (!p_node.isSeq() || p_node.size() != p_count) {
		return fail(p_field, "must be a list of " + std::to_string(p_count) + " numbers");
	}
	for (size_t i = 0; i < p_count; i++) {
		if (!number(p_node[static_cast<int>(i)], p_field + "[" + std::to_string(i) + "]", &r_values[i])) {
			return false;
		}
	}
	return true;
}

} // namespace roomprobe
