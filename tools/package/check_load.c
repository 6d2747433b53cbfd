// Loads shared libraries the way Godot loads an extension (dlopen, every symbol bound now) and looks
// up the entry symbol, on whatever system it runs: tests/host/test_package.sh runs it on a bare
// Debian 12 root, with nothing installed but the base system, against the packaged addon.
// Usage: check_load [--entry SYMBOL] LIBRARY...   Exit status 0 when every library loaded.
#include <dlfcn.h>
#include <gnu/libc-version.h>
#include <stdio.h>
#include <string.h>

int main(int argc, char **argv) {
	const char *entry = NULL;
	int loaded = 0;
	printf("glibc %s\n", gnu_get_libc_version());
	for (int i = 1; i < argc; ++i) {
		if (strcmp(argv[i], "--entry") == 0 && i + 1 < argc) {
			entry = argv[++i];
			continue;
		}
		void *handle = dlopen(argv[i], RTLD_NOW | RTLD_LOCAL);
		if (!handle) {
			printf("cannot load %s: %s\n", argv[i], dlerror());
			return 1;
		}
		if (entry && !dlsym(handle, entry)) {
			printf("%s has no symbol %s\n", argv[i], entry);
			return 1;
		}
		printf("loaded %s%s%s\n", argv[i], entry ? ", found " : "", entry ? entry : "");
		entry = NULL;
		++loaded;
	}
	return loaded > 0 ? 0 : 2;
}
