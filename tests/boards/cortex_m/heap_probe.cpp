// Must NOT link: proves that the link-time heap ban works (test heap_use_fails_link).
#include <cstdlib>

int main() {
  void* volatile p = std::malloc(16);
  std::free(p);
  return 0;
}
