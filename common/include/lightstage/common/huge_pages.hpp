#pragma once
// Large buffers filled once from end to end (a stack's observation matrices)
// page-fault once per 4 kB page as they are first written, which costs more
// than the writing itself in a virtual machine. Where the kernel backs memory
// with 2 MB pages on request (transparent_hugepage = madvise, Debian's
// default), asking for them first makes that one fault per 2 MB.

#include <cstddef>

namespace lightstage {

// Asks for 2 MB pages over the whole 2 MB pages inside [data, data + bytes).
// Call it before the buffer is first written. A hint only: nothing changes
// where the kernel does not give them, and no error is reported.
void advise_huge_pages(void* data, std::size_t bytes);

}  // namespace lightstage
