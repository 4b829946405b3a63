/* Zero-filled aligned heap blocks for the whole process.
 *
 * libx264 reads a few bytes of buffers it allocated (x264_malloc -> memalign) before writing
 * them. Left as glibc hands them out, those bytes are whatever the process freed there before,
 * so an episode's video bytes depended on the episodes recorded before it in the same process,
 * and so on --jobs (measured: a few LSBs, PSNR 65-85 dB, between --jobs 1, 2 and 3). The
 * fetchscope executable therefore defines the aligned allocators itself (exported through
 * heap_zero.list, so libx264 and libavcodec bind to them) and clears every block they hand out.
 * Plain malloc/free stay glibc's: clearing freed memory as well (glibc's M_PERTURB) made Mesa's
 * llvmpipe crash with two GL contexts in one process (--worker-mode thread).
 */
#include <errno.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

extern void* __libc_memalign(size_t alignment, size_t size);

static void* ZeroedAligned(size_t alignment, size_t size) {
  void* p = __libc_memalign(alignment, size);
  if (p) memset(p, 0, size);
  return p;
}

void* memalign(size_t alignment, size_t size) { return ZeroedAligned(alignment, size); }

void* aligned_alloc(size_t alignment, size_t size) { return ZeroedAligned(alignment, size); }

int posix_memalign(void** out, size_t alignment, size_t size) {
  if (alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0 || alignment == 0) {
    return EINVAL;
  }
  void* p = ZeroedAligned(alignment, size);
  if (!p && size != 0) return ENOMEM;
  *out = p;
  return 0;
}
