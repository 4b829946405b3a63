/* Linked into the sanitizer build only (FETCHSCOPE_SANITIZE): makes dlclose a no-op, so the GL
 * drivers (Mesa's swrast/llvmpipe, loaded by libEGL/libOSMesa) stay mapped until exit. Otherwise
 * LeakSanitizer reports their one-time allocations from "<unknown module>" frames that no
 * suppression in lsan.supp can name. An executable's definition wins over libc's for every
 * library in the process. */
int dlclose(void* handle) {
  (void)handle;
  return 0;
}
