// Preloaded into Godot, before the sanitizer's runtime, when the godot suite runs against a sanitized
// library (./roomprobe test --sanitize ... --suite godot; tools/testrun/sanitize.py). Godot opens a
// GDExtension with dlopen(RTLD_NOW | RTLD_DEEPBIND) unless Godot itself was built with sanitizers, and
// the sanitizers' dlopen ends the process on RTLD_DEEPBIND (google/sanitizers#611: a library bound to
// itself first would call libc's malloc and friends, not the sanitizer's). This dlopen drops that one
// flag and calls the next dlopen (the sanitizer's). Without it, the library binds to the process's
// symbols first, as it does in Godot's own sanitizer builds; it is built with hidden visibility, so
// it resolves its own functions itself either way. Not instrumented: it runs before any runtime.
#define _GNU_SOURCE
#include <dlfcn.h>

void *dlopen(const char *p_file, int p_flags) {
	static void *(*next)(const char *, int);
	if (!next) {
		next = (void *(*)(const char *, int))dlsym(RTLD_NEXT, "dlopen");
	}
	return next(p_file, p_flags & ~RTLD_DEEPBIND);
}
