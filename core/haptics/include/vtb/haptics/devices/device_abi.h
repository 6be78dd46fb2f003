/* The device plug-in interface of vtb (C ABI, docs/devices.md "Writing a device driver").
 *
 * A plug-in is a shared library that exports one function, `vtb_device_entry`, which vtb loads
 * at run time (`[haptics] device = "plugin"`, `plugin = PATH`, or `vtb haptics --device
 * plugin:PATH`). vtb calls it with the ABI version it speaks; the plug-in returns its table
 * of functions, whose `abi_version` vtb checks: a table of another version is refused in one
 * line, before any function of it is called.
 *
 * Threads: open and close are called from the session's main thread; read, write and advance
 * only from the servo thread, once per servo cycle, and must neither block nor allocate.
 *
 * Safety: vtb clamps every commanded force to the smaller of the device's and the scene's
 * limit, ramps it in, and sends zero on a fault (a read that fails or returns a non-finite
 * value), on a stall of the physics and before close, whatever the plug-in does.
 */
#ifndef VTB_HAPTICS_DEVICE_ABI_H
#define VTB_HAPTICS_DEVICE_ABI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define VTB_DEVICE_ABI_VERSION 1u
#define VTB_DEVICE_ENTRY_SYMBOL "vtb_device_entry"

/* What the device is, filled by open. Every field has a default set by vtb before the call
 * (the scene's limit, 2000 N/m, the ProCAT's workspace); a plug-in overwrites what it knows. */
typedef struct vtb_device_info {
  char name[64];           /* shown on the run line and in summary.json */
  double max_force;        /* N: the device's own limit */
  double max_stiffness;    /* N/m: the stiffest coupling it renders stably */
  double workspace_min[2]; /* m, device coordinates */
  double workspace_max[2]; /* m */
} vtb_device_info;

/* One reading of the handle, in the device's plane (m, m/s). */
typedef struct vtb_device_state {
  double position[2];
  double velocity[2];
} vtb_device_state;

/* One servo cycle's command: the force to render now, and the local model about it, so that a
 * driver running faster than the servo can render between cycles:
 *   F(x) = force - stiffness (x - anchor)   (anchor: the handle where force was computed). */
typedef struct vtb_device_command {
  double force[2];  /* N, already clamped by vtb */
  double stiffness; /* N/m, >= 0 */
  double anchor[2]; /* m */
  double time;      /* s: the servo's clock */
} vtb_device_command;

typedef struct vtb_device_api {
  uint32_t abi_version; /* VTB_DEVICE_ABI_VERSION of the header the plug-in was built with */
  /* Opens the device; config is the scene's [haptics] text for it (may be empty). Returns the
   * device's handle, or NULL with a one-line reason in error (at most error_size bytes). */
  void* (*open)(const char* config, vtb_device_info* info, char* error, size_t error_size);
  /* Reads the handle: 0 on success, non-zero on a fault (vtb then renders 0 N). */
  int (*read)(void* device, vtb_device_state* state);
  /* Sends one command: 0 on success, non-zero on a fault. */
  int (*write)(void* device, const vtb_device_command* command);
  /* A simulated device's own physics over dt seconds (NULL for hardware). */
  void (*advance)(void* device, double dt);
  /* Closes the device; vtb has sent a zero force just before. */
  void (*close)(void* device);
} vtb_device_api;

/* The one exported function: the plug-in's table for a host speaking host_abi_version. */
typedef const vtb_device_api* (*vtb_device_entry_fn)(uint32_t host_abi_version);

#ifdef __cplusplus
}
#endif

#endif /* VTB_HAPTICS_DEVICE_ABI_H */
