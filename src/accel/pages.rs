//! Large arrays the traversal reads at random (the wide BVH's nodes and octets) on 2 MiB pages
//! where the system gives them on request: Linux's transparent huge pages in their `madvise`
//! mode, the common default. A ray that points anywhere reads nodes and triangles from all
//! over tens of megabytes; on 4 KiB pages nearly every one of those reads also misses the
//! address translation cache, and a miss walks the page tables (twice over in a virtual
//! machine). Embree asks for huge pages for the same reason.

/// The size of a huge page on x86-64 and AArch64 Linux.
const HUGE_PAGE: usize = 2 << 20;

/// `items` moved into a new allocation whose whole 2 MiB pages are advised to be huge before
/// they are first written (an array smaller than two such pages is left where it is: it could
/// hold none). Where the system has no such pages the advice does nothing.
pub fn on_huge_pages<T: Copy>(items: Vec<T>) -> Vec<T> {
    let bytes = std::mem::size_of_val(&items[..]);
    if bytes < 2 * HUGE_PAGE || !cfg!(target_os = "linux") {
        return items;
    }
    let mut moved = Vec::with_capacity(items.len());
    advise_huge(moved.as_mut_ptr() as usize, bytes);
    moved.extend_from_slice(&items);
    moved
}

/// Advises the whole huge pages of `bytes` bytes from `start` to be huge.
#[cfg(target_os = "linux")]
fn advise_huge(start: usize, bytes: usize) {
    let first = start.next_multiple_of(HUGE_PAGE);
    let end = (start + bytes) / HUGE_PAGE * HUGE_PAGE;
    if end > first {
        // SAFETY: the range lies within an allocation this process owns; advice changes no
        // contents, and a refusal (no huge pages in this kernel) changes nothing.
        unsafe { libc::madvise(first as *mut libc::c_void, end - first, libc::MADV_HUGEPAGE) };
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge(_start: usize, _bytes: usize) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_items_move_unchanged() {
        for len in [0, 5, HUGE_PAGE, 3 * HUGE_PAGE + 7] {
            let items: Vec<u32> = (0..len as u32)
                .map(|i| i.wrapping_mul(2_654_435_761))
                .collect();
            assert_eq!(on_huge_pages(items.clone()), items, "{len} items");
        }
    }
}
