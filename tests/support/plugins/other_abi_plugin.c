/* A device plug-in built against another ABI version: vtb must refuse it in one line, before
 * calling any of its functions (each aborts if called). */
#include "vtb/haptics/devices/device_abi.h"

#include <stdlib.h>

static void* never_open(const char* c, vtb_device_info* i, char* e, size_t n) {
  (void)c, (void)i, (void)e, (void)n;
  abort();
}
static int never_read(void* d, vtb_device_state* s) {
  (void)d, (void)s;
  abort();
}
static int never_write(void* d, const vtb_device_command* c) {
  (void)d, (void)c;
  abort();
}
static void never_close(void* d) {
  (void)d;
  abort();
}

static const vtb_device_api api = {VTB_DEVICE_ABI_VERSION + 1, never_open, never_read, never_write, NULL, never_close};

const vtb_device_api* vtb_device_entry(uint32_t host_abi_version) {
  (void)host_abi_version;
  return &api;
}
