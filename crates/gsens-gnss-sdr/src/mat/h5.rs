//! A reader of the part of HDF5 that a MATLAB v7.3 file written by matio uses
//! for numeric arrays, and nothing more: every structure outside that part is
//! refused with a sentence naming what was found, and every offset, length and
//! count read from the file is checked against the file before use, so that a
//! damaged file gives an error, never a panic or an unbounded allocation.
//!
//! The part read:
//! - the superblock, version 0 or 1, at byte 0, 512, 1024, … (matio puts it
//!   after a 512-byte MATLAB header, the HDF5 "user block"), with 8-byte
//!   offsets and lengths;
//! - the root group as a symbol table: a version-1 B-tree of symbol-table
//!   nodes whose names are in a local heap;
//! - version-1 object headers (with continuation blocks), and of their
//!   messages: dataspace (simple or scalar), datatype (little-endian IEEE
//!   binary32/binary64, little-endian 32/64-bit integers), data layout
//!   (versions 1–3: compact, contiguous, or chunked with a version-1 B-tree)
//!   and the filter pipeline (deflate only).

use miniz_oxide::inflate::decompress_to_vec_zlib_with_limit;

/// An error: what was found where, as a sentence.
pub(crate) type H5Result<T> = Result<T, String>;

const SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";
/// The "undefined address" of the format.
const UNDEFINED: u64 = u64::MAX;
/// At most this many B-tree nodes, symbol-table nodes and header blocks are
/// visited in one file: far more than any real file of arrays has, few enough
/// that a file whose nodes point at each other is refused quickly.
const NODE_BUDGET: usize = 100_000;
/// Deflate expands at most about 1032-fold: no real dataset holds more bytes
/// than this many times the file's size.
const MAX_EXPANSION: usize = 1100;
/// The most dimensions a dataspace may have (the format's own limit).
const MAX_RANK: usize = 32;
/// The most members a root group may have here: a tracking dump has some 25.
const MAX_MEMBERS: usize = 4096;
/// The longest member name read: MATLAB's variable names have at most 63 bytes.
const MAX_NAME: usize = 1024;

/// An array's element type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ElemType {
    /// IEEE binary32.
    F32,
    /// IEEE binary64.
    F64,
    /// Unsigned 32-bit integer.
    U32,
    /// Unsigned 64-bit integer.
    U64,
    /// Signed 32-bit integer.
    I32,
}

impl ElemType {
    /// Its size in bytes.
    pub(crate) fn size(self) -> usize {
        match self {
            ElemType::F32 | ElemType::U32 | ElemType::I32 => 4,
            ElemType::F64 | ElemType::U64 => 8,
        }
    }
}

/// A dataset as read: its shape, element type and elements as little-endian
/// bytes in row-major order.
pub(crate) struct Array {
    /// The dataspace's dimensions (empty for a scalar).
    pub(crate) shape: Vec<u64>,
    /// The element type.
    pub(crate) ty: ElemType,
    /// `shape.product() * ty.size()` bytes.
    pub(crate) bytes: Vec<u8>,
}

/// Bounds-checked little-endian reads from a byte slice.
struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
    /// What is being read, for errors.
    what: &'static str,
}

impl<'a> Reader<'a> {
    fn new(buf: &'a [u8], what: &'static str) -> Self {
        Reader { buf, pos: 0, what }
    }

    fn take(&mut self, n: usize) -> H5Result<&'a [u8]> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.buf.len()).ok_or_else(|| {
            format!("the {} ends at byte {} of {} while {n} more were expected", self.what, self.pos, self.buf.len())
        })?;
        let s = &self.buf[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn skip(&mut self, n: usize) -> H5Result<()> {
        self.take(n).map(|_| ())
    }

    fn u8(&mut self) -> H5Result<u8> {
        Ok(self.take(1)?[0])
    }

    fn u16(&mut self) -> H5Result<u16> {
        let b = self.take(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    fn u32(&mut self) -> H5Result<u32> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn u64(&mut self) -> H5Result<u64> {
        let b = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }

    /// A structure's 4-byte signature and version byte, as expected.
    fn signature(&mut self, signature: &[u8; 4], version: u8, addr: u64) -> H5Result<()> {
        let what = self.what;
        if self.take(4)? != signature {
            let sig = String::from_utf8_lossy(signature);
            return Err(format!("no {what} (signature {sig}) at address {addr}"));
        }
        let found = self.u8()?;
        if found != version {
            return Err(format!("{what} version {found} at address {addr}; this reader knows version {version}"));
        }
        Ok(())
    }

    fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }
}

/// A B-tree node's children: each one's left key and address.
type Children<'a> = Vec<(&'a [u8], u64)>;

/// A chunk as its B-tree indexes it.
struct Chunk {
    /// Its stored (filtered) size.
    size: u32,
    /// Bit k set: filter k skipped.
    mask: u32,
    /// Its first element's place in the dataset.
    offset: Vec<u64>,
    /// Its address.
    addr: u64,
}

/// What a dataset's layout is read with.
struct Meta<'s> {
    shape: &'s [u64],
    ty: ElemType,
    /// Its size in bytes.
    total: usize,
    /// Whether its pipeline deflates.
    deflate: bool,
    /// Its name, for errors.
    what: &'s str,
}

/// A version-1 object header's message: its type and its bytes.
struct Message<'a> {
    kind: u16,
    flags: u8,
    data: &'a [u8],
}

/// An HDF5 file held in memory.
pub(crate) struct H5File<'a> {
    buf: &'a [u8],
    /// The absolute position every address is relative to.
    base: u64,
    /// The root group's object header.
    root: u64,
    /// Nodes, blocks and entries still allowed to be visited.
    budget: std::cell::Cell<usize>,
    /// Bytes of data still allowed to be produced: deflate's greatest
    /// expansion of the whole file, so that datasets sharing one header or one
    /// run of chunks cannot multiply it.
    data_budget: std::cell::Cell<u64>,
}

impl<'a> H5File<'a> {
    /// Finds and checks the superblock.
    pub(crate) fn open(buf: &'a [u8]) -> H5Result<Self> {
        let mut at = 0usize;
        let start = loop {
            if buf.len().saturating_sub(at) < SIGNATURE.len() {
                return Err(format!(
                    "no HDF5 signature at byte 0 or at any power of two from 512 to the end ({} bytes)",
                    buf.len()
                ));
            }
            if &buf[at..at + SIGNATURE.len()] == SIGNATURE {
                break at;
            }
            at = if at == 0 { 512 } else { at * 2 };
        };
        let mut r = Reader::new(&buf[start..], "superblock");
        r.skip(8)?;
        let version = r.u8()?;
        if version > 1 {
            return Err(format!(
                "superblock version {version} at byte {start} (a file written for HDF5 1.8 or later); \
                 this reader knows versions 0 and 1, which matio writes"
            ));
        }
        r.skip(4)?; // free-space, root-group and shared-header versions, a reserved byte
        let (offsets, lengths) = (r.u8()?, r.u8()?);
        if offsets != 8 || lengths != 8 {
            return Err(format!(
                "the superblock gives {offsets}-byte addresses and {lengths}-byte lengths; this reader knows 8 and 8"
            ));
        }
        r.skip(1 + 2 + 2 + 4)?; // reserved, group leaf and internal K, consistency flags
        if version == 1 {
            r.skip(4)?; // indexed-storage K and reserved
        }
        let base = r.u64()?;
        r.skip(8 + 8 + 8)?; // free-space, end-of-file and driver-information addresses
        // The root group's symbol-table entry: name offset, then its object header.
        r.skip(8)?;
        let root = r.u64()?;
        let data_budget = (buf.len() as u64).saturating_mul(MAX_EXPANSION as u64).max(1 << 24);
        Ok(H5File {
            buf,
            base,
            root,
            budget: std::cell::Cell::new(NODE_BUDGET),
            data_budget: std::cell::Cell::new(data_budget),
        })
    }

    /// Counts `n` nodes, blocks or entries against the file's budget.
    fn spend(&self, n: usize, what: &str) -> H5Result<()> {
        let left = self.budget.get().checked_sub(n).ok_or_else(|| {
            format!("more than {NODE_BUDGET} nodes, blocks and entries met reading the {what}: a loop?")
        })?;
        self.budget.set(left);
        Ok(())
    }

    /// `len` bytes at address `addr`.
    fn at(&self, addr: u64, len: u64, what: &str) -> H5Result<&'a [u8]> {
        if addr == UNDEFINED {
            return Err(format!("the {what} has no address"));
        }
        let start = self.base.checked_add(addr);
        let end = start.and_then(|s| s.checked_add(len));
        match (start, end) {
            (Some(s), Some(e)) if e <= self.buf.len() as u64 => Ok(&self.buf[s as usize..e as usize]),
            _ => Err(format!(
                "the {what} ({len} bytes at address {addr}, base {}) lies beyond the file's {} bytes",
                self.base,
                self.buf.len()
            )),
        }
    }

    /// The bytes from address `addr` to the end of the file.
    fn from(&self, addr: u64, what: &str) -> H5Result<&'a [u8]> {
        let len = (self.buf.len() as u64).saturating_sub(self.base.saturating_add(addr));
        self.at(addr, len, what)
    }

    /// The root group's members: each name and its object header's address, in the B-tree's order.
    pub(crate) fn members(&self) -> H5Result<Vec<(String, u64)>> {
        let messages = self.messages(self.root, "root group")?;
        let Some(st) = messages.iter().find(|m| m.kind == 0x11) else {
            let kinds: Vec<String> = messages.iter().map(|m| format!("{:#06x}", m.kind)).collect();
            return Err(format!(
                "the root group has no symbol-table message (its header holds messages [{}]; \
                 a group of link messages is written by HDF5 1.8's newer format, not by matio)",
                kinds.join(", ")
            ));
        };
        let mut r = Reader::new(st.data, "root group's symbol-table message");
        let (btree, heap) = (r.u64()?, r.u64()?);
        let names = self.local_heap(heap)?;
        let mut entries = Vec::new();
        self.group_node(btree, None, &mut entries)?;
        if entries.len() > MAX_MEMBERS {
            return Err(format!(
                "the root group holds {} members, more than the {MAX_MEMBERS} read here",
                entries.len()
            ));
        }
        entries
            .into_iter()
            .map(|(offset, header)| {
                let tail = usize::try_from(offset).ok().and_then(|o| names.get(o..)).ok_or_else(|| {
                    format!("a member's name is at offset {offset} of a local heap of {} bytes", names.len())
                })?;
                let end = tail.iter().take(MAX_NAME + 1).position(|&b| b == 0).ok_or_else(|| {
                    format!("a member's name at heap offset {offset} runs off the local heap or past {MAX_NAME} bytes")
                })?;
                let name = std::str::from_utf8(&tail[..end])
                    .map_err(|_| format!("a member's name at heap offset {offset} is not UTF-8"))?;
                Ok((name.to_owned(), header))
            })
            .collect()
    }

    /// A local heap's data segment.
    fn local_heap(&self, addr: u64) -> H5Result<&'a [u8]> {
        let mut r = Reader::new(self.at(addr, 32, "local heap")?, "local heap");
        r.signature(b"HEAP", 0, addr)?;
        r.skip(3)?;
        let size = r.u64()?;
        r.skip(8)?; // the free list
        let data = r.u64()?;
        self.at(data, size, "local heap's data segment")
    }

    /// Collects the (name offset, object header) entries under a group B-tree node.
    fn group_node(&self, addr: u64, level: Option<u8>, out: &mut Vec<(u64, u64)>) -> H5Result<()> {
        self.spend(1, "root group")?;
        let (node_level, children) = self.btree_node(addr, 0, 8, "group B-tree node")?;
        if let Some(expected) = level
            && node_level != expected
        {
            return Err(format!("a group B-tree node at address {addr} is at level {node_level}, not {expected}"));
        }
        for (_, child) in children {
            if node_level > 0 {
                self.group_node(child, Some(node_level - 1), out)?;
            } else {
                self.symbol_node(child, out)?;
            }
        }
        Ok(())
    }

    /// A version-1 B-tree node of `node_type` whose keys are `key_len` bytes:
    /// its level and each child's (left key, address).
    fn btree_node(&self, addr: u64, node_type: u8, key_len: usize, what: &'static str) -> H5Result<(u8, Children<'a>)> {
        let mut r = Reader::new(self.from(addr, what)?, what);
        if r.take(4)? != b"TREE" {
            return Err(format!("no B-tree node (signature TREE) at address {addr}"));
        }
        let ty = r.u8()?;
        if ty != node_type {
            return Err(format!("the B-tree node at address {addr} is of type {ty}, not {node_type}"));
        }
        let level = r.u8()?;
        let entries = usize::from(r.u16()?);
        r.skip(16)?; // siblings
        let mut children = Vec::with_capacity(entries.min(r.remaining() / (key_len + 8)));
        for _ in 0..entries {
            let key = r.take(key_len)?;
            children.push((key, r.u64()?));
        }
        r.skip(key_len)?;
        Ok((level, children))
    }

    /// Collects the entries of a symbol-table node.
    fn symbol_node(&self, addr: u64, out: &mut Vec<(u64, u64)>) -> H5Result<()> {
        self.spend(1, "root group")?;
        let mut r = Reader::new(self.from(addr, "symbol-table node")?, "symbol-table node");
        r.signature(b"SNOD", 1, addr)?;
        r.skip(1)?;
        let count = r.u16()?;
        self.spend(usize::from(count), "root group")?;
        for _ in 0..count {
            let name = r.u64()?;
            let header = r.u64()?;
            r.skip(4 + 4 + 16)?; // cache type, reserved, scratch pad
            out.push((name, header));
        }
        Ok(())
    }

    /// The messages of the version-1 object header at `addr`, continuation blocks followed.
    fn messages(&self, addr: u64, what: &str) -> H5Result<Vec<Message<'a>>> {
        let head = self.at(addr, 16, &format!("{what}'s object header"))?;
        if &head[..4] == b"OHDR" {
            return Err(format!(
                "the {what}'s object header is of version 2 (HDF5 1.8's newer format); \
                 this reader knows version 1, which matio writes"
            ));
        }
        let mut r = Reader::new(head, "object header");
        let version = r.u8()?;
        if version != 1 {
            return Err(format!("the {what}'s object header at address {addr} is of version {version}, not 1"));
        }
        r.skip(1 + 2 + 4)?; // reserved, message count, reference count
        let size = r.u32()?;
        let mut blocks = vec![self.at(addr + 16, u64::from(size), &format!("{what}'s object header"))?];
        let mut messages = Vec::new();
        while let Some(block) = blocks.pop() {
            self.spend(1, what)?;
            let mut r = Reader::new(block, "object header message");
            while r.remaining() >= 8 {
                let kind = r.u16()?;
                let len = r.u16()?;
                let flags = r.u8()?;
                r.skip(3)?;
                let data = r.take(usize::from(len))?;
                self.spend(1, what)?;
                if kind == 0x10 {
                    let mut c = Reader::new(data, "continuation message");
                    let (at, len) = (c.u64()?, c.u64()?);
                    blocks.push(self.at(at, len, &format!("{what}'s header continuation"))?);
                } else if kind != 0 {
                    messages.push(Message { kind, flags, data });
                }
            }
        }
        Ok(messages)
    }

    /// Reads the dataset whose object header is at `addr`; `what` names it in errors.
    pub(crate) fn dataset(&self, addr: u64, what: &str) -> H5Result<Array> {
        let messages = self.messages(addr, what)?;
        let find = |kind: u16, name: &str| {
            let m = messages
                .iter()
                .find(|m| m.kind == kind)
                .ok_or_else(|| format!("{what} has no {name} message: not a dataset"))?;
            if m.flags & 0x02 != 0 {
                return Err(format!("{what}'s {name} message is shared (stored elsewhere in the file); not read here"));
            }
            Ok(m.data)
        };
        let shape = dataspace(find(0x01, "dataspace")?, what)?;
        let ty = datatype(find(0x03, "datatype")?, what)?;
        let layout = find(0x08, "data-layout")?;
        let deflate = match messages.iter().find(|m| m.kind == 0x0B) {
            Some(m) => filters(m.data, what)?,
            None => false,
        };
        let mut count: u64 = 1;
        for &d in &shape {
            count = count.checked_mul(d).ok_or_else(|| format!("{what}'s dimensions {shape:?} overflow"))?;
        }
        let esize = ty.size() as u64;
        let left = self.data_budget.get();
        let total = count.checked_mul(esize).filter(|&t| t <= left).ok_or_else(|| {
            format!("{what}'s dimensions {shape:?}, with the datasets read before it, hold more data than a file of its size can")
        })?;
        self.data_budget.set(left - total);
        let meta = Meta { shape: &shape, ty, total: total as usize, deflate, what };
        let bytes = self.layout(layout, &meta)?;
        Ok(Array { shape, ty, bytes })
    }

    /// The dataset's `total` bytes as its layout message places them.
    fn layout(&self, msg: &[u8], meta: &Meta<'_>) -> H5Result<Vec<u8>> {
        let &Meta { total, deflate, what, .. } = meta;
        let mut r = Reader::new(msg, "data-layout message");
        let version = r.u8()?;
        let (class, chunk_dims, address, stored): (u8, Vec<u64>, u64, Option<&[u8]>);
        match version {
            1 | 2 => {
                let rank = usize::from(r.u8()?);
                class = r.u8()?;
                r.skip(5)?;
                address = if class == 0 { UNDEFINED } else { r.u64()? };
                let mut dims = Vec::with_capacity(rank.min(MAX_RANK + 1));
                for _ in 0..rank {
                    dims.push(u64::from(r.u32()?));
                }
                stored = if class == 0 {
                    let size = r.u32()? as usize;
                    Some(r.take(size)?)
                } else {
                    None
                };
                chunk_dims = dims;
            }
            3 => {
                class = r.u8()?;
                match class {
                    0 => {
                        let size = usize::from(r.u16()?);
                        stored = Some(r.take(size)?);
                        address = UNDEFINED;
                        chunk_dims = Vec::new();
                    }
                    1 => {
                        address = r.u64()?;
                        let size = r.u64()?;
                        if size < total as u64 {
                            return Err(format!("{what} is stored in {size} bytes, but its dimensions need {total}"));
                        }
                        stored = None;
                        chunk_dims = Vec::new();
                    }
                    2 => {
                        let rank = usize::from(r.u8()?);
                        address = r.u64()?;
                        let mut dims = Vec::with_capacity(rank);
                        for _ in 0..rank {
                            dims.push(u64::from(r.u32()?));
                        }
                        stored = None;
                        chunk_dims = dims;
                    }
                    other => return Err(format!("{what} has a data layout of class {other}, unknown")),
                }
            }
            other => {
                return Err(format!(
                    "{what} has a data-layout message of version {other} (HDF5 1.10's chunk indexes); \
                     this reader knows versions 1 to 3, which matio writes"
                ));
            }
        }
        if deflate && class != 2 {
            return Err(format!("{what} has a deflate filter but is not chunked"));
        }
        match class {
            0 => {
                let data = stored.unwrap_or_default();
                data.get(..total).map(<[u8]>::to_vec).ok_or_else(|| {
                    format!("{what} holds {} bytes in its header, but its dimensions need {total}", data.len())
                })
            }
            1 => {
                if total == 0 {
                    return Ok(Vec::new());
                }
                Ok(self.at(address, total as u64, &format!("{what}'s data"))?.to_vec())
            }
            2 => self.chunked(address, &chunk_dims, meta),
            other => Err(format!("{what} has a data layout of class {other}, unknown")),
        }
    }

    /// Assembles a chunked dataset from the chunks its B-tree indexes.
    fn chunked(&self, btree: u64, chunk_dims: &[u64], meta: &Meta<'_>) -> H5Result<Vec<u8>> {
        let &Meta { shape, ty, total, deflate, what } = meta;
        let esize = ty.size();
        let rank = shape.len();
        if chunk_dims.len() != rank + 1 || chunk_dims[rank] != esize as u64 {
            return Err(format!(
                "{what}'s chunks have dimensions {chunk_dims:?}, not its {rank} dimensions and its {esize}-byte element"
            ));
        }
        let chunk_dims = &chunk_dims[..rank];
        if chunk_dims.contains(&0) {
            return Err(format!("{what}'s chunks have a zero dimension: {chunk_dims:?}"));
        }
        let chunk_bytes = chunk_dims
            .iter()
            .try_fold(esize as u64, |a, &d| a.checked_mul(d))
            .filter(|&b| b <= self.data_budget.get())
            .and_then(|b| usize::try_from(b).ok())
            .ok_or_else(|| format!("{what}'s chunks of {chunk_dims:?} are larger than a file of its size can hold"))?;
        let mut chunks = Vec::new();
        self.chunk_node(btree, None, rank, &mut chunks)?;
        let mut out = vec![0u8; total];
        let mut filled = vec![false; total / esize];
        for Chunk { size, mask, offset, addr } in chunks {
            // Every chunk costs its size from the file's data budget: chunks that repeat without
            // end, in one dataset or across many, are refused.
            let left = self.data_budget.get();
            self.data_budget.set(left.checked_sub(chunk_bytes as u64).ok_or_else(|| {
                format!("{what}'s chunks, with the data read before them, hold more than a file of its size can")
            })?);
            let raw = self.at(addr, u64::from(size), &format!("a chunk of {what}"))?;
            let owned;
            let data = if deflate && mask & 1 == 0 {
                owned = decompress_to_vec_zlib_with_limit(raw, chunk_bytes)
                    .map_err(|e| format!("a chunk of {what} at address {addr} does not inflate: {:?}", e.status))?;
                &owned[..]
            } else {
                raw
            };
            if data.len() != chunk_bytes {
                return Err(format!(
                    "a chunk of {what} at address {addr} holds {} bytes, not the {chunk_bytes} of a chunk",
                    data.len()
                ));
            }
            copy_chunk(data, &offset, chunk_dims, shape, esize, &mut out, &mut filled);
        }
        if let Some(k) = filled.iter().position(|&f| !f) {
            return Err(format!("element {k} of {what} lies in no chunk (unwritten chunks are not read here)"));
        }
        Ok(out)
    }

    /// Collects the chunks under a chunk B-tree node.
    fn chunk_node(&self, addr: u64, level: Option<u8>, rank: usize, out: &mut Vec<Chunk>) -> H5Result<()> {
        self.spend(1, "chunk index")?;
        let key_len = 8 + 8 * (rank + 1);
        let (node_level, children) = self.btree_node(addr, 1, key_len, "chunk B-tree node")?;
        if let Some(expected) = level
            && node_level != expected
        {
            return Err(format!("a chunk B-tree node at address {addr} is at level {node_level}, not {expected}"));
        }
        for (key, child) in children {
            if node_level > 0 {
                self.chunk_node(child, Some(node_level - 1), rank, out)?;
            } else {
                self.spend(1, "chunk index")?;
                let mut k = Reader::new(key, "chunk key");
                let size = k.u32()?;
                let mask = k.u32()?;
                let offset = (0..rank).map(|_| k.u64()).collect::<H5Result<Vec<u64>>>()?;
                out.push(Chunk { size, mask, offset, addr: child });
            }
        }
        Ok(())
    }
}

/// Copies the elements of one chunk at `offset` that lie inside `shape` to
/// their row-major places in `out`, marking them in `filled`.
fn copy_chunk(
    data: &[u8],
    offset: &[u64],
    chunk_dims: &[u64],
    shape: &[u64],
    esize: usize,
    out: &mut [u8],
    filled: &mut [bool],
) {
    let rank = shape.len();
    let mut local = vec![0u64; rank];
    for element in data.chunks_exact(esize) {
        // The element's place in the dataset, if inside it.
        let mut index: u64 = 0;
        let mut inside = true;
        for d in 0..rank {
            match offset[d].checked_add(local[d]) {
                Some(g) if g < shape[d] => index = index * shape[d] + g,
                _ => {
                    inside = false;
                    break;
                }
            }
        }
        if inside {
            let i = index as usize;
            out[i * esize..(i + 1) * esize].copy_from_slice(element);
            filled[i] = true;
        }
        // The next element in the chunk, last dimension fastest.
        for d in (0..rank).rev() {
            local[d] += 1;
            if local[d] < chunk_dims[d] {
                break;
            }
            local[d] = 0;
        }
    }
}

/// A dataspace message's dimensions.
fn dataspace(msg: &[u8], what: &str) -> H5Result<Vec<u64>> {
    let mut r = Reader::new(msg, "dataspace message");
    let version = r.u8()?;
    let rank = usize::from(r.u8()?);
    let _flags = r.u8()?;
    match version {
        1 => r.skip(5)?,
        2 => match r.u8()? {
            0 => return Ok(Vec::new()),
            1 => {}
            _ => return Err(format!("{what} has an empty (null) dataspace")),
        },
        other => return Err(format!("{what} has a dataspace message of version {other}; known: 1 and 2")),
    }
    if rank > MAX_RANK {
        return Err(format!("{what} has {rank} dimensions, more than HDF5's {MAX_RANK}"));
    }
    (0..rank).map(|_| r.u64()).collect()
}

/// A datatype message's element type, if one of those read here.
fn datatype(msg: &[u8], what: &str) -> H5Result<ElemType> {
    let mut r = Reader::new(msg, "datatype message");
    let class_version = r.u8()?;
    let bits = r.take(3)?;
    let size = r.u32()?;
    let class = class_version & 0x0f;
    let big_endian = bits[0] & 0x01 != 0;
    let found = match class {
        0 => {
            let signed = bits[0] & 0x08 != 0;
            let (offset, precision) = (r.u16()?, r.u16()?);
            let whole = offset == 0 && u32::from(precision) == size * 8;
            match (big_endian, signed, size, whole) {
                (false, false, 4, true) => return Ok(ElemType::U32),
                (false, false, 8, true) => return Ok(ElemType::U64),
                (false, true, 4, true) => return Ok(ElemType::I32),
                _ => format!(
                    "a {}-endian {} integer of {size} bytes ({precision} bits at bit {offset})",
                    if big_endian { "big" } else { "little" },
                    if signed { "signed" } else { "unsigned" }
                ),
            }
        }
        1 => {
            let vax = bits[0] & 0x40 != 0;
            let normalization = (bits[0] >> 4) & 0x03;
            let sign = bits[1];
            let (offset, precision) = (r.u16()?, r.u16()?);
            let (exp_at, exp_bits, mant_at, mant_bits) = (r.u8()?, r.u8()?, r.u8()?, r.u8()?);
            let bias = r.u32()?;
            let layout = (offset, precision, exp_at, exp_bits, mant_at, mant_bits, bias, sign, normalization);
            match (big_endian, vax, size) {
                (false, false, 4) if layout == (0, 32, 23, 8, 0, 23, 127, 31, 2) => return Ok(ElemType::F32),
                (false, false, 8) if layout == (0, 64, 52, 11, 0, 52, 1023, 63, 2) => return Ok(ElemType::F64),
                _ => format!(
                    "a {size}-byte {} floating-point type (exponent {exp_bits} bits at {exp_at}, mantissa \
                     {mant_bits} bits at {mant_at}, bias {bias}){}",
                    if big_endian { "big-endian" } else { "little-endian" },
                    if vax { ", VAX order" } else { "" }
                ),
            }
        }
        other => {
            let name = match other {
                2 => "time",
                3 => "string",
                4 => "bit field",
                5 => "opaque",
                6 => "compound",
                7 => "reference",
                8 => "enumeration",
                9 => "variable-length",
                10 => "array",
                _ => "unknown",
            };
            format!("a {name} type (class {other}) of {size} bytes")
        }
    };
    Err(format!(
        "{what} is of {found}; a dump's arrays are little-endian IEEE binary32/binary64, uint32, uint64 or int32"
    ))
}

/// Whether a filter-pipeline message asks for deflate; any other filter is refused.
fn filters(msg: &[u8], what: &str) -> H5Result<bool> {
    let mut r = Reader::new(msg, "filter-pipeline message");
    let version = r.u8()?;
    let count = r.u8()?;
    match version {
        1 => r.skip(6)?,
        2 => {}
        other => return Err(format!("{what} has a filter-pipeline message of version {other}; known: 1 and 2")),
    }
    let mut deflate = false;
    for k in 0..count {
        let id = r.u16()?;
        let name_len = if version == 1 || id >= 256 { usize::from(r.u16()?) } else { 0 };
        r.skip(2)?; // flags
        let values = usize::from(r.u16()?);
        let name_len = if version == 1 { name_len.div_ceil(8) * 8 } else { name_len };
        r.skip(name_len)?;
        r.skip(values * 4)?;
        if version == 1 && values % 2 == 1 {
            r.skip(4)?;
        }
        match id {
            1 if k == 0 => deflate = true,
            _ => {
                let name = match id {
                    1 => "deflate (a second time)",
                    2 => "shuffle",
                    3 => "Fletcher-32",
                    4 => "szip",
                    5 => "n-bit",
                    6 => "scale-offset",
                    _ => "a third-party filter",
                };
                return Err(format!("{what} is filtered by filter {id} ({name}); this reader knows deflate alone"));
            }
        }
    }
    Ok(deflate)
}
