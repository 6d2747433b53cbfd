#pragma once
// Godot's ERR_FAIL_* family: report through the engine's error log, then bail out.

#include <rp_godot/variant/variant.h>

namespace godot::internal {
void report_error(const char *p_function, const char *p_file, int p_line, const char *p_condition, const char *p_message, bool p_warning = false);
void report_error(const char *p_function, const char *p_file, int p_line, const char *p_condition, const String &p_message, bool p_warning = false);
} // namespace godot::internal

#define RP_REPORT(m_cond, m_msg, m_warn) ::godot::internal::report_error(__FUNCTION__, __FILE__, __LINE__, m_cond, m_msg, m_warn)

#define ERR_FAIL_COND(m_cond) \
	if (m_cond) [[unlikely]] { RP_REPORT("Condition \"" #m_cond "\" is true.", "", false); return; } else ((void)0)
#define ERR_FAIL_COND_MSG(m_cond, m_msg) \
	if (m_cond) [[unlikely]] { RP_REPORT("Condition \"" #m_cond "\" is true.", m_msg, false); return; } else ((void)0)
#define ERR_FAIL_COND_V(m_cond, m_ret) \
	if (m_cond) [[unlikely]] { RP_REPORT("Condition \"" #m_cond "\" is true. Returning: " #m_ret, "", false); return m_ret; } else ((void)0)
#define ERR_FAIL_COND_V_MSG(m_cond, m_ret, m_msg) \
	if (m_cond) [[unlikely]] { RP_REPORT("Condition \"" #m_cond "\" is true. Returning: " #m_ret, m_msg, false); return m_ret; } else ((void)0)
#define ERR_FAIL_NULL(m_param) \
	if ((m_param) == nullptr) [[unlikely]] { RP_REPORT("Parameter \"" #m_param "\" is null.", "", false); return; } else ((void)0)
#define ERR_FAIL_NULL_V(m_param, m_ret) \
	if ((m_param) == nullptr) [[unlikely]] { RP_REPORT("Parameter \"" #m_param "\" is null.", "", false); return m_ret; } else ((void)0)
#define ERR_FAIL_NULL_MSG(m_param, m_msg) \
	if ((m_param) == nullptr) [[unlikely]] { RP_REPORT("Parameter \"" #m_param "\" is null.", m_msg, false); return; } else ((void)0)
#define ERR_FAIL_NULL_V_MSG(m_param, m_ret, m_msg) \
	if ((m_param) == nullptr) [[unlikely]] { RP_REPORT("Parameter \"" #m_param "\" is null.", m_msg, false); return m_ret; } else ((void)0)
#define ERR_FAIL_INDEX(m_index, m_size) \
	if ((m_index) < 0 || (m_index) >= (m_size)) [[unlikely]] { RP_REPORT("Index " #m_index " is out of bounds (" #m_size ").", "", false); return; } else ((void)0)
#define ERR_FAIL_INDEX_V(m_index, m_size, m_ret) \
	if ((m_index) < 0 || (m_index) >= (m_size)) [[unlikely]] { RP_REPORT("Index " #m_index " is out of bounds (" #m_size ").", "", false); return m_ret; } else ((void)0)
#define ERR_PRINT(m_msg) RP_REPORT("", m_msg, false)
#define WARN_PRINT(m_msg) RP_REPORT("", m_msg, true)
