/* Executes RDTSCP in a static constructor, before main, as Highway's hwy::platform::
 * TimerResolution does when libavcodec loads libhwy (through libjxl): the instruction that
 * Debian 12's valgrind cannot decode on hosts whose CPU does not advertise it
 * (tests/valgrind_probe_test.cc, tools/valgrind-probe.sh). Exits 0 when the counter moved. */
#include <x86intrin.h>

static unsigned long long first, second;

__attribute__((constructor)) static void ReadCounterTwice(void) {
  unsigned int aux;
  first = __rdtscp(&aux);
  second = __rdtscp(&aux);
}

int main(void) { return second > first ? 0 : 1; }
