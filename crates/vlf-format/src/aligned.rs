//! An owned byte buffer that starts on a 64-byte boundary, so a field's sections (which the
//! format places at multiples of 64) can be cast in place from it, as from a memory map.

use crate::error::FormatError;

/// Owned bytes whose first byte is 64-byte aligned.
///
/// Allocated zeroed and untouched, so a large buffer costs address space, not memory, until its
/// pages are written; allocation failure is an error ([`FormatError::OutOfMemory`]), not an
/// abort. Buffers of [`HUGE_PAGE`] and more are an anonymous memory map whose bytes start on a
/// huge-page boundary, advised (on Linux) to be backed by huge pages: a field held in memory (a
/// packed field decoded, `Field::read`) is queried with as few TLB misses as a mapped one. Smaller
/// ones come from the allocator's zeroing path (`calloc` on Unix).
pub struct AlignedBytes {
    storage: Storage,
    /// Offset in bytes of the first byte in `storage`.
    start: usize,
    len: usize,
}

enum Storage {
    Words(Box<[u64]>),
    Map(memmap2::MmapMut),
}

/// The huge page of x86-64 and of aarch64 with 4 KiB pages: 2 MiB.
pub const HUGE_PAGE: usize = 2 << 20;

/// Words of slack so that a 64-byte boundary falls inside the allocation.
const SLACK: usize = 64 / size_of::<u64>() - 1;

impl AlignedBytes {
    /// `len` zero bytes.
    pub fn zeroed(len: u64) -> Result<AlignedBytes, FormatError> {
        let oom = FormatError::OutOfMemory { bytes: len };
        let len_usize = usize::try_from(len).map_err(|_| oom.clone())?;
        if len_usize >= HUGE_PAGE {
            // A huge page of slack, so that one boundary falls where the bytes can start.
            let total = len_usize.checked_add(HUGE_PAGE).ok_or(oom.clone())?;
            let map = memmap2::MmapMut::map_anon(total).map_err(|_| oom)?;
            let start = (HUGE_PAGE - map.as_ptr() as usize % HUGE_PAGE) % HUGE_PAGE;
            // Only a hint: where the kernel does not take it, the bytes are ordinary pages.
            #[cfg(target_os = "linux")]
            let _ = map.advise_range(memmap2::Advice::HugePage, start, len_usize);
            return Ok(AlignedBytes { storage: Storage::Map(map), start, len: len_usize });
        }
        let words = len_usize.div_ceil(size_of::<u64>()).checked_add(SLACK).ok_or(oom.clone())?;
        let words: Box<[u64]> = bytemuck::allocation::try_zeroed_slice_box(words).map_err(|()| oom)?;
        let misalignment = words.as_ptr() as usize % 64;
        let start = if misalignment == 0 { 0 } else { 64 - misalignment };
        Ok(AlignedBytes { storage: Storage::Words(words), start, len: len_usize })
    }

    /// A 64-byte-aligned copy of `bytes`.
    pub fn copy_of(bytes: &[u8]) -> Result<AlignedBytes, FormatError> {
        let mut b = AlignedBytes::zeroed(bytes.len() as u64)?;
        b.as_bytes_mut().copy_from_slice(bytes);
        Ok(b)
    }

    pub fn as_bytes(&self) -> &[u8] {
        let all: &[u8] = match &self.storage {
            Storage::Words(words) => bytemuck::cast_slice(words),
            Storage::Map(map) => map,
        };
        &all[self.start..self.start + self.len]
    }

    pub fn as_bytes_mut(&mut self) -> &mut [u8] {
        let all: &mut [u8] = match &mut self.storage {
            Storage::Words(words) => bytemuck::cast_slice_mut(words),
            Storage::Map(map) => map,
        };
        &mut all[self.start..self.start + self.len]
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl std::fmt::Debug for AlignedBytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "AlignedBytes({} bytes)", self.len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_on_a_cache_line_and_holds_exactly_len_bytes() {
        for len in [0u64, 1, 7, 8, 63, 64, 65, 1000] {
            let mut b = AlignedBytes::zeroed(len).unwrap();
            assert_eq!(b.as_bytes().as_ptr() as usize % 64, 0);
            assert_eq!(b.len() as u64, len);
            assert!(b.as_bytes().iter().all(|&x| x == 0));
            b.as_bytes_mut().fill(0xab);
            let c = AlignedBytes::copy_of(b.as_bytes()).unwrap();
            assert_eq!(c.as_bytes(), b.as_bytes());
        }
    }

    /// A buffer of a huge page and more starts on a huge-page boundary (where the kernel can back
    /// it with huge pages), zeroed, and holds exactly its bytes.
    #[test]
    fn a_large_buffer_starts_on_a_huge_page() {
        for len in [HUGE_PAGE as u64, 3 * HUGE_PAGE as u64 + 5] {
            let mut b = AlignedBytes::zeroed(len).unwrap();
            assert_eq!(b.as_bytes().as_ptr() as usize % HUGE_PAGE, 0);
            assert_eq!(b.len() as u64, len);
            assert!(b.as_bytes().iter().all(|&x| x == 0));
            b.as_bytes_mut().fill(0xcd);
            assert!(AlignedBytes::copy_of(b.as_bytes()).unwrap().as_bytes() == b.as_bytes());
        }
    }

    #[test]
    fn an_impossible_size_is_an_error_not_an_abort() {
        let err = AlignedBytes::zeroed(u64::MAX / 2).unwrap_err();
        assert!(matches!(err, FormatError::OutOfMemory { .. }), "{err}");
    }
}
