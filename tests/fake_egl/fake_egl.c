// A stand-in libEGL.so.1 that presents NVIDIA's EGL to fetchscope on a machine without an
// NVIDIA GPU, so that CI exercises the code paths of a GPU node: NVIDIA's exact extension
// strings (../shared/reference/gpu-node-measurements.md), several devices with EGL_NV_device_cuda
// ordinals, a device that fails to initialise, or none at all. Rendering itself is forwarded to
// the real libEGL (Mesa's surfaceless platform, llvmpipe), so frames are real.
//
// Configuration (environment, read at the first call):
//   FAKE_EGL_DEVICES  comma list, one entry per device in EGL order: "cuda=N" (the physical
//                     CUDA ordinal), optionally with ":fail" (eglInitialize fails with
//                     EGL_NOT_INITIALIZED); empty: no devices at all. Unset: one device, cuda=0.
//   FAKE_EGL_REAL     the real libEGL to forward to (default: the multiarch libEGL.so.1).
//   FAKE_EGL_LOG      a file to which each eglInitialize appends "pid P init device D\n"
//                     (D = -1 for the surfaceless display).
// EGL_CUDA_DEVICE_NV reports the ordinal in the process's CUDA numbering, as NVIDIA's driver
// does: the position of the physical ordinal in CUDA_VISIBLE_DEVICES when that is set, and the
// query fails for a device that CUDA_VISIBLE_DEVICES hides.
#define _GNU_SOURCE
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define MAX_DEVICES 16
#define EGL_CUDA_DEVICE_NV_VALUE 0x323A

// NVIDIA driver 580's strings, as measured on an H100 node.
static const char kClientExtensions[] =
    "EGL_EXT_platform_base EGL_EXT_device_base EGL_KHR_client_get_all_proc_addresses "
    "EGL_EXT_client_extensions EGL_KHR_debug EGL_KHR_platform_x11 EGL_EXT_platform_x11 "
    "EGL_EXT_platform_device EGL_MESA_platform_surfaceless EGL_EXT_explicit_device";
static const char kDeviceExtensions[] =
    "EGL_NV_device_cuda EGL_EXT_device_drm EGL_EXT_device_drm_render_node "
    "EGL_EXT_device_query_name EGL_EXT_device_persistent_id";

struct FakeDevice {
  int cuda_physical;
  int fails;
};

// A display handed out by the fake: the real display plus the device it stands for.
struct FakeDisplay {
  EGLDisplay real;
  int device;  // -1: surfaceless
};

static struct FakeDevice g_devices[MAX_DEVICES];
static struct FakeDisplay g_displays[MAX_DEVICES + 1];
static int g_device_count;
static void* g_real;
static EGLint g_error = EGL_SUCCESS;  // our own last error, reported once
static pthread_once_t g_once = PTHREAD_ONCE_INIT;

#define REAL(name) ((__typeof__(&name))real_symbol(#name))

static void* real_symbol(const char* name);

static void load(void) {
  const char* real = getenv("FAKE_EGL_REAL");
  if (!real || !*real) real = "/usr/lib/x86_64-linux-gnu/libEGL.so.1";
  // No RTLD_DEEPBIND (AddressSanitizer refuses it): libglvnd's libEGL is linked -Bsymbolic, so
  // its calls to its own egl* functions never reach ours of the same names, and dlsym on its
  // handle searches only its own dependency scope. The check below catches a real library
  // that would resolve to this fake.
  g_real = dlopen(real, RTLD_NOW | RTLD_LOCAL);
  if (!g_real) {
    fprintf(stderr, "fake libEGL: cannot load the real libEGL %s: %s\n", real, dlerror());
    abort();
  }
  if (dlsym(g_real, "eglGetProcAddress") == (void*)&eglGetProcAddress) {
    fprintf(stderr, "fake libEGL: FAKE_EGL_REAL=%s resolves to this fake, not a real libEGL\n",
            real);
    abort();
  }
  const char* spec = getenv("FAKE_EGL_DEVICES");
  if (!spec) spec = "cuda=0";
  char buffer[512];
  snprintf(buffer, sizeof(buffer), "%s", spec);
  char* save = NULL;
  for (char* item = strtok_r(buffer, ",", &save); item && g_device_count < MAX_DEVICES;
       item = strtok_r(NULL, ",", &save)) {
    struct FakeDevice* d = &g_devices[g_device_count++];
    d->cuda_physical = -1;
    sscanf(item, "cuda=%d", &d->cuda_physical);
    d->fails = strstr(item, ":fail") != NULL;
  }
  for (int i = 0; i <= MAX_DEVICES; ++i) g_displays[i].real = EGL_NO_DISPLAY;
}

static void* real_symbol(const char* name) {
  pthread_once(&g_once, load);
  void* fn = dlsym(g_real, name);
  if (!fn) {
    fprintf(stderr, "fake libEGL: the real libEGL lacks %s\n", name);
    abort();
  }
  return fn;
}

static struct FakeDisplay* find_display(EGLDisplay display) {
  for (int i = 0; i <= MAX_DEVICES; ++i) {
    if ((EGLDisplay)&g_displays[i] == display) return &g_displays[i];
  }
  return NULL;
}

static EGLDisplay real_display(EGLDisplay display) {
  struct FakeDisplay* fake = find_display(display);
  return fake ? fake->real : display;
}

// The CUDA ordinal of physical device `physical` in this process, or -1 when hidden.
static int visible_ordinal(int physical) {
  const char* visible = getenv("CUDA_VISIBLE_DEVICES");
  if (!visible) return physical;
  char buffer[256];
  snprintf(buffer, sizeof(buffer), "%s", visible);
  char* save = NULL;
  int ordinal = 0;
  for (char* item = strtok_r(buffer, ",", &save); item; item = strtok_r(NULL, ",", &save)) {
    if (atoi(item) == physical) return ordinal;
    ++ordinal;
  }
  return -1;
}

static EGLDisplay make_display(int device) {
  struct FakeDisplay* fake = &g_displays[device < 0 ? MAX_DEVICES : device];
  if (fake->real == EGL_NO_DISPLAY) {
    PFNEGLGETPLATFORMDISPLAYEXTPROC get =
        (PFNEGLGETPLATFORMDISPLAYEXTPROC)REAL(eglGetProcAddress)("eglGetPlatformDisplayEXT");
    fake->real = get(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
    fake->device = device;
  }
  return (EGLDisplay)fake;
}

static EGLBoolean fake_query_devices(EGLint max, EGLDeviceEXT* devices, EGLint* count) {
  pthread_once(&g_once, load);
  if (!count) {
    g_error = EGL_BAD_PARAMETER;
    return EGL_FALSE;
  }
  if (!devices) {
    *count = g_device_count;
    return EGL_TRUE;
  }
  int n = max < g_device_count ? max : g_device_count;
  for (int i = 0; i < n; ++i) devices[i] = (EGLDeviceEXT)&g_devices[i];
  *count = n;
  return EGL_TRUE;
}

static int device_index(EGLDeviceEXT device) {
  for (int i = 0; i < g_device_count; ++i) {
    if ((EGLDeviceEXT)&g_devices[i] == device) return i;
  }
  return -1;
}

static const char* fake_query_device_string(EGLDeviceEXT device, EGLint name) {
  if (device_index(device) < 0) {
    g_error = EGL_BAD_DEVICE_EXT;
    return NULL;
  }
  if (name == EGL_EXTENSIONS) return kDeviceExtensions;
  // NVIDIA answers no EGL_DRM_DEVICE_FILE_EXT on a node without /dev/dri
  g_error = EGL_BAD_PARAMETER;
  return NULL;
}

static EGLBoolean fake_query_device_attrib(EGLDeviceEXT device, EGLint attribute,
                                           EGLAttrib* value) {
  int index = device_index(device);
  if (index < 0) {
    g_error = EGL_BAD_DEVICE_EXT;
    return EGL_FALSE;
  }
  if (attribute != EGL_CUDA_DEVICE_NV_VALUE) {
    g_error = EGL_BAD_ATTRIBUTE;
    return EGL_FALSE;
  }
  int ordinal = visible_ordinal(g_devices[index].cuda_physical);
  if (ordinal < 0) {
    g_error = EGL_BAD_ATTRIBUTE;
    return EGL_FALSE;
  }
  *value = ordinal;
  return EGL_TRUE;
}

static EGLDisplay fake_get_platform_display(EGLenum platform, void* native,
                                            const EGLint* attributes) {
  (void)attributes;
  pthread_once(&g_once, load);
  if (platform == EGL_PLATFORM_DEVICE_EXT) {
    int index = device_index((EGLDeviceEXT)native);
    if (index < 0) {
      g_error = EGL_BAD_PARAMETER;
      return EGL_NO_DISPLAY;
    }
    return make_display(index);
  }
  if (platform == EGL_PLATFORM_SURFACELESS_MESA) return make_display(-1);
  g_error = EGL_BAD_PARAMETER;
  return EGL_NO_DISPLAY;
}

// ---- exported EGL 1.4 entry points ----

__eglMustCastToProperFunctionPointerType eglGetProcAddress(const char* name) {
  if (!strcmp(name, "eglQueryDevicesEXT")) {
    return (__eglMustCastToProperFunctionPointerType)fake_query_devices;
  }
  if (!strcmp(name, "eglQueryDeviceStringEXT")) {
    return (__eglMustCastToProperFunctionPointerType)fake_query_device_string;
  }
  if (!strcmp(name, "eglQueryDeviceAttribEXT")) {
    return (__eglMustCastToProperFunctionPointerType)fake_query_device_attrib;
  }
  if (!strcmp(name, "eglGetPlatformDisplayEXT")) {
    return (__eglMustCastToProperFunctionPointerType)fake_get_platform_display;
  }
  return REAL(eglGetProcAddress)(name);
}

EGLint eglGetError(void) {
  if (g_error != EGL_SUCCESS) {
    EGLint e = g_error;
    g_error = EGL_SUCCESS;
    return e;
  }
  return REAL(eglGetError)();
}

const char* eglQueryString(EGLDisplay display, EGLint name) {
  if (display == EGL_NO_DISPLAY && name == EGL_EXTENSIONS) return kClientExtensions;
  return REAL(eglQueryString)(real_display(display), name);
}

EGLBoolean eglInitialize(EGLDisplay display, EGLint* major, EGLint* minor) {
  struct FakeDisplay* fake = find_display(display);
  const char* log = getenv("FAKE_EGL_LOG");
  if (log && *log && fake) {
    FILE* f = fopen(log, "a");
    if (f) {
      fprintf(f, "pid %d init device %d%s\n", (int)getpid(), fake->device,
              fake->device >= 0 && g_devices[fake->device].fails ? " (fails)" : "");
      fclose(f);
    }
  }
  if (fake && fake->device >= 0 && g_devices[fake->device].fails) {
    g_error = EGL_NOT_INITIALIZED;
    return EGL_FALSE;
  }
  return REAL(eglInitialize)(real_display(display), major, minor);
}

EGLBoolean eglTerminate(EGLDisplay display) { return REAL(eglTerminate)(real_display(display)); }

EGLBoolean eglBindAPI(EGLenum api) { return REAL(eglBindAPI)(api); }

EGLBoolean eglChooseConfig(EGLDisplay display, const EGLint* attributes, EGLConfig* configs,
                           EGLint size, EGLint* count) {
  return REAL(eglChooseConfig)(real_display(display), attributes, configs, size, count);
}

EGLContext eglCreateContext(EGLDisplay display, EGLConfig config, EGLContext share,
                            const EGLint* attributes) {
  return REAL(eglCreateContext)(real_display(display), config, share, attributes);
}

EGLBoolean eglDestroyContext(EGLDisplay display, EGLContext context) {
  return REAL(eglDestroyContext)(real_display(display), context);
}

EGLSurface eglCreatePbufferSurface(EGLDisplay display, EGLConfig config, const EGLint* attributes) {
  return REAL(eglCreatePbufferSurface)(real_display(display), config, attributes);
}

EGLBoolean eglDestroySurface(EGLDisplay display, EGLSurface surface) {
  return REAL(eglDestroySurface)(real_display(display), surface);
}

EGLBoolean eglMakeCurrent(EGLDisplay display, EGLSurface draw, EGLSurface read,
                          EGLContext context) {
  return REAL(eglMakeCurrent)(real_display(display), draw, read, context);
}

EGLContext eglGetCurrentContext(void) { return REAL(eglGetCurrentContext)(); }

EGLBoolean eglReleaseThread(void) { return REAL(eglReleaseThread)(); }
