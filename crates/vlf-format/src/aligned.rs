//! An owned byte buffer that starts on a 64-byte boundary, so a field's sections (which the
//! format places at multiples of 64) can be cast in place from it, as from a memory map.

use crate::error::FormatError;

/// Owned bytes whose first byte is 64-byte aligned.
///
/// Allocated zeroed through the allocator's zeroing path (`calloc` on Unix), so a large buffer
/// costs address space, not memory, until its pages are written; allocation failure is an error
/// ([`FormatError::OutOfMemory`]), not an abort.
pub struct AlignedBytes {
    words: Box<[u64]>,
    /// Index of the first word that belongs to the bytes (the first 64-byte-aligned word).
    start: usize,
    len: usize,
}

/// Words of slack so that a 64-byte boundary falls inside the allocation.
const SLACK: usize = 64 / size_of::<u64>() - 1;

impl AlignedBytes {
    /// `len` zero bytes.
    pub fn zeroed(len: u64) -> Result<AlignedBytes, FormatError> {
        let oom = FormatError::OutOfMemory { bytes: len };
        let len_usize = usize::try_from(len).map_err(|_| oom.clone())?;
        let words = len_usize.div_ceil(size_of::<u64>()).checked_add(SLACK).ok_or(oom.clone())?;
        let words: Box<[u64]> = bytemuck::allocation::try_zeroed_slice_box(words).map_err(|()| oom)?;
        let misalignment = (words.as_ptr() as usize % 64) / size_of::<u64>();
        let start = if misalignment == 0 { 0 } else { 8 - misalignment };
        Ok(AlignedBytes { words, start, len: len_usize })
    }

    /// A 64-byte-aligned copy of `bytes`.
    pub fn copy_of(bytes: &[u8]) -> Result<AlignedBytes, FormatError> {
        let mut b = AlignedBytes::zeroed(bytes.len() as u64)?;
        b.as_bytes_mut().copy_from_slice(bytes);
        Ok(b)
    }

    pub fn as_bytes(&self) -> &[u8] {
        &bytemuck::cast_slice(&self.words[self.start..])[..self.len]
    }

    pub fn as_bytes_mut(&mut self) -> &mut [u8] {
        &mut bytemuck::cast_slice_mut(&mut self.words[self.start..])[..self.len]
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

    #[test]
    fn an_impossible_size_is_an_error_not_an_abort() {
        let err = AlignedBytes::zeroed(u64::MAX / 2).unwrap_err();
        assert!(matches!(err, FormatError::OutOfMemory { .. }), "{err}");
    }
}
