//! Two slots of NOR flash holding a log of records; the newest intact one is the saved model
//! (see [`FlashStore`]).

use core::fmt;
use core::ops::Range;

use embedded_storage::nor_flash::{NorFlash, NorFlashError};

use super::codec::{HEADER, Head, MIN_LEN};
use super::crc32::Crc32;
use super::{DecodeError, EncodeError, MAGIC, Record};

/// Bytes staged per flash read or write; `READ_SIZE` and `WRITE_SIZE` must divide it.
const CHUNK: usize = 256;
/// Bytes an entry adds to its record: the sequence number and its complement.
const SEQUENCE: usize = 8;

/// A model store in a region of NOR flash, safe against a power cut at any point of a save.
///
/// The region (whole erase units) is split into two slots of equal size. A slot holds a log
/// of entries, each a [record](super) followed by a sequence number and its bitwise
/// complement (both `u32`, little-endian), padded with `0xFF` to a multiple of `WRITE_SIZE`:
///
/// | slot offset | bytes | field |
/// |---|---|---|
/// | `e` | `L` | the record (its magic `IMAR` first, its length and CRC-32 included) |
/// | `e + L` | 4 | sequence number `s` |
/// | `e + L + 4` | 4 | `!s` |
/// | `e + L + 8` | to a multiple of `WRITE_SIZE` | `0xFF` |
///
/// Entries are written from their first byte to their last, so the sequence number is the
/// commit: an entry is *intact* when its record's length and CRC-32 check (whatever its kind)
/// and `!s` matches `s` after it. Where an entry was begun, its first byte (`I`) is no longer
/// `0xFF`; the log ends at the first entry whose magic reads erased. [`FlashStore::load`]
/// returns the intact entry with the newest sequence number (compared modulo 2^32, so the
/// numbers may wrap). [`FlashStore::save`] appends the new entry, numbered one past the
/// newest, to the slot that holds the newest while it has room; when it has none (or holds a
/// damaged entry after the newest), it erases the *other* slot and writes the entry at its
/// start. So no save ever erases or writes a byte of the newest intact entry, a slot is
/// erased once per slot-full of saves (about 2,500 saves of an AR(4) `f32` model in a 128 KiB
/// sector), and each write unit is written once between erases, as ECC flash demands.
///
/// What each fault leaves:
///
/// - A power cut while the other slot is erased: that slot holds part of its old entries (all
///   older than the newest) or none; the newest entry is untouched and [`FlashStore::load`]
///   returns it. The next save erases that slot again.
/// - A power cut while an entry is written: the entry is not intact (its tail, with the CRC
///   or the sequence number, is missing or half written), so the previous entry is still the
///   newest and is returned. The next save erases the other slot rather than write after the
///   damaged entry (or over it: its first byte is written).
/// - A power cut after the entry's last byte: the new entry is intact and the newest.
/// - A flash error: [`StoreError::Flash`] with the flash's own error. An erase or write error
///   leaves the newest entry untouched, as a power cut does. A read error ends the scan of
///   that slot at the entry it hit: [`FlashStore::load`] counts the entries before it, and
///   [`FlashStore::save`] writes and erases nothing (the unread part may hold the newest
///   entry, whose number or slot the save would otherwise reuse).
/// - A read-back of the new entry that does not check: [`StoreError::Verify`] (worn or
///   failing flash); the previous entry is still the newest.
/// - Damage at rest (a bit flipped in an entry): that entry is no longer intact. Where its
///   header still reads, the scan steps over it by its length, so that the entries after it
///   still count: damage in the newest entry returns the previous one, one save older; damage
///   in an older one changes nothing. Nothing is written after a damaged entry.
/// - Nothing intact in either slot (erased, or never written by this store):
///   [`StoreError::Empty`].
/// - The newest intact record is of another kind or order, or makes no valid model:
///   [`StoreError::Decode`]; an older record is never returned in its place. A record of
///   another layout version is not intact (its CRC cannot be checked).
///
/// Every `save` and `load` reads the intact entries of both slots and checks their CRCs (so a
/// full slot is read in full); the store keeps no state in RAM beyond the region.
///
/// ```
/// # use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
/// # struct Ram([u8; 2048]);
/// # impl ErrorType for Ram {
/// #     type Error = NorFlashErrorKind;
/// # }
/// # impl ReadNorFlash for Ram {
/// #     const READ_SIZE: usize = 1;
/// #     fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
/// #         let at = offset as usize;
/// #         let src = self.0.get(at..at + bytes.len()).ok_or(NorFlashErrorKind::OutOfBounds)?;
/// #         bytes.copy_from_slice(src);
/// #         Ok(())
/// #     }
/// #     fn capacity(&self) -> usize {
/// #         self.0.len()
/// #     }
/// # }
/// # impl NorFlash for Ram {
/// #     const WRITE_SIZE: usize = 4;
/// #     const ERASE_SIZE: usize = 1024;
/// #     fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
/// #         self.0[from as usize..to as usize].fill(0xFF);
/// #         Ok(())
/// #     }
/// #     fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
/// #         for (cell, b) in self.0[offset as usize..].iter_mut().zip(bytes) {
/// #             *cell &= b; // NOR: a write only clears bits
/// #         }
/// #         Ok(())
/// #     }
/// # }
/// use imu_ar::ArModel;
/// use imu_ar::persist::{FlashStore, Record, StoreError};
///
/// // Two erase units of 1 KiB: one slot each.
/// let mut flash = Ram([0xFF; 2048]);
/// let mut store = FlashStore::new(&mut flash, 0..2048)?;
/// let mut buf = [0u8; ArModel::<f32, 4>::LEN];
/// assert_eq!(store.load::<ArModel<f32, 4>>(&mut buf), Err(StoreError::Empty));
///
/// let model = ArModel::new([0.5f32, 0.1, -0.05, 0.02], 1e-4, 0.0, 0.01)?;
/// store.save(&model, &mut buf)?;
/// assert_eq!(store.load::<ArModel<f32, 4>>(&mut buf)?, model);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct FlashStore<F> {
    flash: F,
    /// Offset of slot 0; slot 1 follows it.
    start: usize,
    slot_len: usize,
}

/// Why a store operation failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StoreError<E> {
    /// The flash returned this error.
    Flash(E),
    /// The region is not whole erase units inside the flash, or holds fewer than two.
    Region,
    /// An entry (the record, 8 bytes of sequence number and the padding) is larger than a
    /// slot.
    TooSmall {
        /// Bytes of the entry.
        needed: usize,
        /// Bytes of a slot.
        slot: usize,
    },
    /// The buffer is shorter than the record.
    Buffer {
        /// The record's length ([`Record::LEN`]).
        needed: usize,
        /// The buffer's length.
        given: usize,
    },
    /// Neither slot holds an intact entry: nothing was stored.
    Empty,
    /// The entry just written does not read back intact.
    Verify,
    /// The model was not encoded (see [`EncodeError`]).
    Encode(EncodeError),
    /// The newest intact record is not a model of the type asked for.
    Decode(DecodeError),
}

impl<E> From<E> for StoreError<E> {
    fn from(e: E) -> Self {
        Self::Flash(e)
    }
}

impl<E: NorFlashError> fmt::Display for StoreError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Flash(e) => write!(f, "flash: {}", e.kind()),
            Self::Region => f.write_str(
                "the store's region must be whole erase units inside the flash, at least two",
            ),
            Self::TooSmall { needed, slot } => {
                write!(
                    f,
                    "an entry of {needed} bytes does not fit a slot of {slot}"
                )
            }
            Self::Buffer { needed, given } => {
                write!(f, "buffer of {given} bytes, the record needs {needed}")
            }
            Self::Empty => f.write_str("no model stored"),
            Self::Verify => f.write_str("the entry written does not read back intact"),
            Self::Encode(e) => write!(f, "{e}"),
            Self::Decode(e) => write!(f, "{e}"),
        }
    }
}

impl<E: NorFlashError> core::error::Error for StoreError<E> {}

/// The intact entries of one slot.
struct Scan<E> {
    /// Sequence number, slot offset and record length of the last intact entry.
    newest: Option<(u32, usize, usize)>,
    /// Where the next entry may be written: after the last intact entry, when the magic
    /// there reads erased; `None` after a damaged entry or a read error.
    free: Option<usize>,
    /// The read error that ended the scan.
    error: Option<E>,
}

/// Whether sequence number `b` is newer than `a` (modulo 2^32).
fn newer(b: u32, a: u32) -> bool {
    b.wrapping_sub(a).cast_signed() > 0
}

impl<F: NorFlash> FlashStore<F> {
    /// A store in `region` (byte offsets into `flash`), whose start and end are multiples of
    /// `ERASE_SIZE`; each slot is half of its erase units (an odd one out stays unused). The
    /// flash's `READ_SIZE` and `WRITE_SIZE` must divide 256 (a compile-time check). Nothing is
    /// read or written here. Pass `&mut flash` to keep the flash (`NorFlash` is implemented
    /// for `&mut F`).
    ///
    /// # Errors
    ///
    /// [`StoreError::Region`] for a region that is not aligned to `ERASE_SIZE`, ends beyond
    /// the flash's capacity, or holds fewer than two erase units.
    pub fn new(flash: F, region: Range<u32>) -> Result<Self, StoreError<F::Error>> {
        const {
            assert!(
                F::READ_SIZE > 0
                    && F::WRITE_SIZE > 0
                    && CHUNK.is_multiple_of(F::READ_SIZE)
                    && CHUNK.is_multiple_of(F::WRITE_SIZE)
                    && F::ERASE_SIZE.is_multiple_of(F::READ_SIZE)
                    && F::ERASE_SIZE.is_multiple_of(F::WRITE_SIZE),
                "READ_SIZE and WRITE_SIZE must divide 256 and ERASE_SIZE"
            )
        };
        let (Ok(start), Ok(end)) = (usize::try_from(region.start), usize::try_from(region.end))
        else {
            return Err(StoreError::Region);
        };
        let unit = F::ERASE_SIZE;
        let aligned = unit > 0 && start.is_multiple_of(unit) && end.is_multiple_of(unit);
        let units = end.saturating_sub(start) / unit.max(1);
        if !aligned || end > flash.capacity() || units < 2 {
            return Err(StoreError::Region);
        }
        Ok(Self {
            flash,
            start,
            slot_len: (units / 2).saturating_mul(unit),
        })
    }

    /// The bytes of each slot.
    pub fn slot_len(&self) -> usize {
        self.slot_len
    }

    /// The flash, back.
    pub fn destroy(self) -> F {
        self.flash
    }

    /// Saves `model` as the newest entry (see [`FlashStore`] for where it goes and what a
    /// power cut leaves), encoding it in `buf` (at least [`Record::LEN`] bytes), erasing a
    /// slot when needed and reading the entry back. Returns its sequence number.
    ///
    /// # Errors
    ///
    /// [`StoreError::Buffer`] for a short buffer; [`StoreError::Encode`] for a model that
    /// does not encode; [`StoreError::TooSmall`] when the entry is larger than a slot;
    /// [`StoreError::Flash`] for a flash error; [`StoreError::Verify`] when the entry does not
    /// read back intact. Nothing is erased or written before the first three are ruled out.
    pub fn save<M: Record>(
        &mut self,
        model: &M,
        buf: &mut [u8],
    ) -> Result<u32, StoreError<F::Error>> {
        let len = model.encode(buf).map_err(|e| match e {
            EncodeError::Buffer { needed, given } => StoreError::Buffer { needed, given },
            e => StoreError::Encode(e),
        })?;
        let entry = self.entry_len(len);
        if entry > self.slot_len {
            return Err(StoreError::TooSmall {
                needed: entry,
                slot: self.slot_len,
            });
        }
        let [mut a, mut b] = [self.scan(0), self.scan(1)];
        // A slot that cannot be read in full may hide the newest entry: numbering or placing
        // the new one from what could be read might reuse its number or erase it.
        if let Some(e) = a.error.take().or(b.error.take()) {
            return Err(StoreError::Flash(e));
        }
        let scans = [a, b];
        let newest = Self::newest(&scans);
        let seq = match newest.and_then(|s| scans.get(s)?.newest) {
            Some((s, ..)) if s.wrapping_add(1) != u32::MAX => s.wrapping_add(1),
            _ => 0,
        };
        // After the newest entry, in its slot, while there is room; else at the start of the
        // other slot, erased.
        let room = |s: &Scan<F::Error>| s.free.filter(|f| f.saturating_add(entry) <= self.slot_len);
        let append = newest.and_then(|s| Some((s, room(scans.get(s)?)?)));
        let (slot, pos) = match append {
            Some(found) => found,
            None => {
                let other = usize::from(newest == Some(0));
                let base = self.base(other);
                let end = base.saturating_add(self.slot_len);
                self.flash.erase(Self::at(base)?, Self::at(end)?)?;
                (other, 0)
            }
        };
        let body = buf.get(..len).unwrap_or(&[]);
        self.write_entry(self.base(slot).saturating_add(pos), seq, body)?;
        match self.scan(slot).newest {
            Some((s, p, l)) if (s, p, l) == (seq, pos, len) => Ok(seq),
            _ => Err(StoreError::Verify),
        }
    }

    /// The model in the newest intact entry, read into `buf` (at least [`Record::LEN`]
    /// bytes) and decoded.
    ///
    /// # Errors
    ///
    /// [`StoreError::Buffer`] for a short buffer; [`StoreError::Empty`] when neither slot
    /// holds an intact entry; [`StoreError::Decode`] when the newest is not a valid `M` (of
    /// another kind or order, say); [`StoreError::Flash`] for a flash error where no intact
    /// entry was found before it.
    pub fn load<M: Record>(&mut self, buf: &mut [u8]) -> Result<M, StoreError<F::Error>> {
        if buf.len() < M::LEN {
            return Err(StoreError::Buffer {
                needed: M::LEN,
                given: buf.len(),
            });
        }
        let scans = [self.scan(0), self.scan(1)];
        let found = Self::newest(&scans).and_then(|s| Some((s, scans.get(s)?.newest?)));
        let Some((slot, (_, pos, _))) = found else {
            // A slot that cannot be read is an error, not an empty store.
            let [a, b] = scans.map(|s| s.error);
            return Err(a.or(b).map_or(StoreError::Empty, StoreError::Flash));
        };
        let record = self.base(slot).saturating_add(pos);
        let given = buf.len();
        let Some((head, rest)) = buf.split_at_mut_checked(HEADER) else {
            return Err(StoreError::Buffer {
                needed: M::LEN,
                given,
            });
        };
        self.read(record, head)?;
        Head::read(head)
            .and_then(|h| h.expect::<M>())
            .map_err(StoreError::Decode)?;
        let tail = rest.get_mut(..M::LEN - HEADER).unwrap_or(&mut []);
        self.read(record.saturating_add(HEADER), tail)?;
        M::decode(buf).map_err(StoreError::Decode)
    }

    fn base(&self, slot: usize) -> usize {
        self.start
            .saturating_add(slot.saturating_mul(self.slot_len))
    }

    /// A flash offset; every offset the store forms lies inside the region [`Self::new`]
    /// checked.
    fn at(offset: usize) -> Result<u32, StoreError<F::Error>> {
        u32::try_from(offset).map_err(|_| StoreError::Region)
    }

    /// Bytes of an entry holding a record of `len` bytes.
    fn entry_len(&self, len: usize) -> usize {
        SEQUENCE
            .saturating_add(len)
            .checked_next_multiple_of(F::WRITE_SIZE.max(1))
            .unwrap_or(usize::MAX)
    }

    /// The slot of the newest intact entry (slot 0 on a tie).
    fn newest(scans: &[Scan<F::Error>; 2]) -> Option<usize> {
        match (scans[0].newest, scans[1].newest) {
            (Some((a, ..)), Some((b, ..))) => Some(usize::from(newer(b, a))),
            (Some(_), None) => Some(0),
            (None, Some(_)) => Some(1),
            (None, None) => None,
        }
    }

    /// The intact entries of `slot`, in order. A damaged entry whose header still reads (a
    /// bit flipped at rest, or a write cut short after its length) is stepped over by its
    /// length, so that intact entries after it still count, but nothing is written after it
    /// (`free` stays `None`); the scan ends at an erased magic, a header that does not read,
    /// a read error or the slot's end.
    fn scan(&mut self, slot: usize) -> Scan<F::Error> {
        let mut scan = Scan {
            newest: None,
            free: None,
            error: None,
        };
        let base = self.base(slot);
        let (mut pos, mut damaged) = (0usize, false);
        while pos.saturating_add(MIN_LEN) <= self.slot_len {
            match self.entry(base.saturating_add(pos), self.slot_len.saturating_sub(pos)) {
                Ok(Entry::Erased) => {
                    scan.free = Some(pos).filter(|_| !damaged);
                    break;
                }
                Ok(Entry::Intact { seq, len }) => {
                    scan.newest = Some((seq, pos, len));
                    pos = pos.saturating_add(self.entry_len(len));
                }
                Ok(Entry::Damaged { len: Some(len) }) => {
                    damaged = true;
                    pos = pos.saturating_add(self.entry_len(len));
                }
                Ok(Entry::Damaged { len: None }) => break,
                Err(e) => {
                    scan.error = Some(e);
                    break;
                }
            }
        }
        scan
    }

    /// The entry at `offset`, with `room` bytes to the slot's end.
    fn entry(&mut self, offset: usize, room: usize) -> Result<Entry, F::Error> {
        let mut head = [0u8; HEADER];
        let n = head.len().min(room);
        let head = head.get_mut(..n).unwrap_or(&mut []);
        self.read(offset, head)?;
        // A record starts with its magic: where an entry was begun, its first byte is not
        // 0xFF.
        if head.iter().take(MAGIC.len()).all(|b| *b == 0xFF) {
            return Ok(Entry::Erased);
        }
        let len = match Head::read(head) {
            Ok(h) if self.entry_len(h.len) <= room => h.len,
            _ => return Ok(Entry::Damaged { len: None }),
        };
        // The CRC of the record's first `len - 4` bytes, against its last four, then the
        // sequence number and its complement.
        let body = len.saturating_sub(MIN_LEN - HEADER);
        let mut crc = Crc32::new();
        self.visit(offset, body, |b| crc.update(b))?;
        let mut tail = [0u8; 4 + SEQUENCE];
        self.read(offset.saturating_add(body), &mut tail)?;
        let [c0, c1, c2, c3, s0, s1, s2, s3, n0, n1, n2, n3] = tail;
        let seq = u32::from_le_bytes([s0, s1, s2, s3]);
        let intact = crc.finish() == u32::from_le_bytes([c0, c1, c2, c3])
            && u32::from_le_bytes([n0, n1, n2, n3]) == !seq;
        Ok(if intact {
            Entry::Intact { seq, len }
        } else {
            Entry::Damaged { len: Some(len) }
        })
    }

    /// Reads `out.len()` bytes at `offset`.
    fn read(&mut self, offset: usize, out: &mut [u8]) -> Result<(), F::Error> {
        let mut at = 0usize;
        self.visit(offset, out.len(), |b| {
            let end = at.saturating_add(b.len());
            if let Some(dst) = out.get_mut(at..end) {
                dst.iter_mut().zip(b).for_each(|(d, s)| *d = *s);
            }
            at = end;
        })
    }

    /// Hands the `len` bytes at `offset` to `f` in order, in pieces, reading through aligned
    /// chunks of at most [`CHUNK`] bytes.
    fn visit(
        &mut self,
        offset: usize,
        len: usize,
        mut f: impl FnMut(&[u8]),
    ) -> Result<(), F::Error> {
        let unit = F::READ_SIZE.max(1);
        let end = offset.saturating_add(len);
        let mut aligned = offset.saturating_sub(offset % unit);
        let mut stage = [0u8; CHUNK];
        while aligned < end {
            let left = end.saturating_sub(aligned);
            let n = left
                .checked_next_multiple_of(unit)
                .map_or(CHUNK, |n| n.min(CHUNK));
            let chunk = stage.get_mut(..n).unwrap_or(&mut []);
            let at = u32::try_from(aligned).unwrap_or(u32::MAX);
            self.flash.read(at, chunk)?;
            let from = offset.saturating_sub(aligned);
            let to = left.min(n);
            f(chunk.get(from..to).unwrap_or(&[]));
            aligned = aligned.saturating_add(n);
        }
        Ok(())
    }

    /// Writes the entry of sequence number `seq` and record `record` at `offset`, in aligned
    /// chunks, each write unit once.
    fn write_entry(
        &mut self,
        offset: usize,
        seq: u32,
        record: &[u8],
    ) -> Result<(), StoreError<F::Error>> {
        let sequence = [seq.to_le_bytes(), (!seq).to_le_bytes()];
        let total = self.entry_len(record.len());
        let padding = total.saturating_sub(SEQUENCE.saturating_add(record.len()));
        let mut bytes = record
            .iter()
            .chain(sequence.iter().flatten())
            .copied()
            .chain(core::iter::repeat_n(0xFF, padding));
        let mut stage = [0xFFu8; CHUNK];
        let mut at = offset;
        let end = offset.saturating_add(total);
        while at < end {
            let n = end.saturating_sub(at).min(CHUNK);
            let chunk = stage.get_mut(..n).unwrap_or(&mut []);
            chunk
                .iter_mut()
                .for_each(|b| *b = bytes.next().unwrap_or(0xFF));
            self.flash.write(Self::at(at)?, chunk)?;
            at = at.saturating_add(n);
        }
        Ok(())
    }
}

/// What the start of an entry says.
enum Entry {
    /// Its magic reads `0xFF`: nothing written from here on.
    Erased,
    /// A sequence number and an intact record of `len` bytes.
    Intact { seq: u32, len: usize },
    /// Anything else; `len` is the record's length where its header still reads.
    Damaged { len: Option<usize> },
}
