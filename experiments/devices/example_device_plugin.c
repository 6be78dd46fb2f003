/* An example device plug-in for vtb (docs/devices.md, "Writing a device driver"): the shape a
 * driver for a vendor's C SDK takes. Its "hardware" is a handle moved along a straight press and
 * held: replace read() and write() with the SDK's calls. Built with the tests
 * (libvtb_example_device.so); run it with
 *   vtb haptics SCENE --device plugin:build/lib/libvtb_example_device.so
 * and [haptics] plugin_config = "from=X,Y to=X,Y seconds=T log=FILE nan_after=N" (each optional):
 * the press's ends (device coordinates, m), its length in s, a file that receives one line at
 * close (the commands received, the largest force, the non-finite ones), and a read that returns
 * NaN after N cycles (to see vtb refuse it).
 */
#include "vtb/haptics/devices/device_abi.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct example_device {
  double from[2], to[2], seconds, t;
  long cycles, nan_after, commands, nonfinite;
  double max_force, max_stiffness_seen;
  char log[512];
} example_device;

static void parse(example_device* d, const char* config) {
  const char* p = config;
  while (p && *p) {
    while (*p == ' ') ++p;
    if (sscanf(p, "from=%lf,%lf", &d->from[0], &d->from[1]) == 2) {
    } else if (sscanf(p, "to=%lf,%lf", &d->to[0], &d->to[1]) == 2) {
    } else if (sscanf(p, "seconds=%lf", &d->seconds) == 1) {
    } else if (sscanf(p, "nan_after=%ld", &d->nan_after) == 1) {
    } else if (strncmp(p, "log=", 4) == 0) {
      size_t n = strcspn(p + 4, " ");
      if (n >= sizeof d->log) n = sizeof d->log - 1;
      memcpy(d->log, p + 4, n);
      d->log[n] = '\0';
    }
    p = strchr(p, ' ');
  }
}

static void* example_open(const char* config, vtb_device_info* info, char* error, size_t error_size) {
  example_device* d = calloc(1, sizeof *d);
  if (!d) {
    snprintf(error, error_size, "out of memory");
    return NULL;
  }
  d->seconds = 1.0;
  d->nan_after = -1;
  parse(d, config);
  if (!(d->seconds > 0)) {
    snprintf(error, error_size, "seconds must be > 0");
    free(d);
    return NULL;
  }
  snprintf(info->name, sizeof info->name, "example-press");
  info->max_force = 3.0; /* this "hardware" renders at most 3 N: vtb keeps the smaller limit */
  return d;
}

static int example_read(void* device, vtb_device_state* s) {
  example_device* d = device;
  const double f = d->t < d->seconds ? d->t / d->seconds : 1.0;
  for (int a = 0; a < 2; ++a) {
    s->position[a] = (1 - f) * d->from[a] + f * d->to[a];
    s->velocity[a] = d->t < d->seconds ? (d->to[a] - d->from[a]) / d->seconds : 0.0;
  }
  if (d->nan_after >= 0 && d->cycles >= d->nan_after) s->position[0] = NAN;
  ++d->cycles;
  return 0;
}

static int example_write(void* device, const vtb_device_command* c) {
  example_device* d = device;
  const double n = sqrt(c->force[0] * c->force[0] + c->force[1] * c->force[1]);
  ++d->commands;
  if (!isfinite(n)) ++d->nonfinite;
  else if (n > d->max_force) d->max_force = n;
  if (c->stiffness > d->max_stiffness_seen) d->max_stiffness_seen = c->stiffness;
  return 0;
}

static void example_advance(void* device, double dt) { ((example_device*)device)->t += dt; }

static void example_close(void* device) {
  example_device* d = device;
  if (d->log[0]) {
    FILE* f = fopen(d->log, "w");
    if (f) {
      fprintf(f, "commands %ld max_force %.17g nonfinite %ld max_stiffness %.17g\n", d->commands, d->max_force,
              d->nonfinite, d->max_stiffness_seen);
      fclose(f);
    }
  }
  free(d);
}

static const vtb_device_api example_api = {VTB_DEVICE_ABI_VERSION, example_open, example_read, example_write,
                                           example_advance, example_close};

const vtb_device_api* vtb_device_entry(uint32_t host_abi_version) {
  return host_abi_version == VTB_DEVICE_ABI_VERSION ? &example_api : NULL;
}
