//! Part files read back: the header, the checks that the parts tile one request, the sections,
//! and the records and sorted columns read through the traits the response builders take.

use super::*;

/// One part file, its header read.
#[derive(Debug)]
pub(super) struct Part {
    pub(super) path: PathBuf,
    pub(super) header: Header,
    pub(super) body_offset: u64,
}

pub(super) fn read_part(path: &Path) -> Result<Part, Failure> {
    let f = File::open(path).map_err(|e| io_err(path, e))?;
    let len = f.metadata().map_err(|e| io_err(path, e))?.len();
    let mut r = BufReader::new(f);
    let mut line = Vec::new();
    r.read_until(b'\n', &mut line)
        .map_err(|e| io_err(path, e))?;
    let not_part = || {
        Failure::from(format!(
            "{}: not a gangue part file (no {FORMAT} header line)",
            path.display()
        ))
    };
    if line.last() != Some(&b'\n') {
        return Err(not_part());
    }
    let v: Value = serde_json::from_slice(&line).map_err(|_| not_part())?;
    if v.get("format").and_then(Value::as_str) != Some(FORMAT) {
        return Err(not_part());
    }
    if v.get("version").and_then(Value::as_u64) != Some(u64::from(FORMAT_VERSION)) {
        return Err(Failure::from(format!(
            "{}: part format version {} cannot be read by this build (it reads version {FORMAT_VERSION})",
            path.display(),
            v.get("version").unwrap_or(&Value::Null)
        )));
    }
    let header: Header = serde_json::from_value(v)
        .map_err(|e| format!("{}: malformed part header: {e}", path.display()))?;
    let body_offset = line.len() as u64;
    let body: u64 = header.sections.iter().sum();
    if len != body_offset + body {
        return Err(Failure::from(format!(
            "{}: the part is {len} bytes, its header says {} (truncated or damaged)",
            path.display(),
            body_offset + body
        )));
    }
    if header.start > header.end || header.end > header.items {
        return Err(Failure::from(format!(
            "{}: item range {}..{} is not within 0..{}",
            path.display(),
            header.start,
            header.end,
            header.items
        )));
    }
    Ok(Part {
        path: path.to_path_buf(),
        header,
        body_offset,
    })
}

/// Checks that the parts come from one request and one build and tile 0..N; sorts them by start.
pub(super) fn check_parts(parts: &mut [Part]) -> Result<(), Failure> {
    let first = parts.first().ok_or("no part files given")?;
    let (h0, p0) = (first.header.clone(), first.path.clone());
    for p in parts.iter() {
        let h = &p.header;
        if h.kind != h0.kind {
            return Err(Failure::from(format!(
                "parts of different kinds of request: {} is {}, {} is {}",
                p0.display(),
                h0.kind,
                p.path.display(),
                h.kind
            )));
        }
        if h.inputs_sha256 != h0.inputs_sha256 || h.items != h0.items {
            return Err(Failure::from(format!(
                "parts of different requests: {} and {} were computed from different inputs \
                 (SHA-256 {} and {}); compute every part from the same request file",
                p0.display(),
                p.path.display(),
                &h0.inputs_sha256[..16.min(h0.inputs_sha256.len())],
                &h.inputs_sha256[..16.min(h.inputs_sha256.len())]
            )));
        }
        if h.build != h0.build {
            return Err(Failure::from(format!(
                "parts of different builds: {} was computed by {}, {} by {}; compute every part \
                 with the same gangue binary",
                p0.display(),
                h0.build,
                p.path.display(),
                h.build
            )));
        }
    }
    parts.sort_by_key(|p| (p.header.start, p.header.end));
    let n = h0.items;
    let mut next = 0u64;
    let mut prev: Option<&Part> = None;
    for p in parts.iter() {
        let h = &p.header;
        if h.start > next {
            return Err(Failure::from(format!(
                "items {next} to {} are missing: no part holds them (the next part, shard {} of \
                 {}, starts at item {}; was a part not computed or not given?)",
                h.start - 1,
                h.shard,
                h.shards,
                h.start
            )));
        }
        if h.start < next && h.end > h.start {
            let q = prev.ok_or_else(|| Failure::from("a part after no part".to_string()))?;
            return Err(Failure::from(format!(
                "items {} to {} are in two parts, {} and {} (a part given twice, or parts of \
                 different splits)",
                h.start,
                next.min(h.end) - 1,
                q.path.display(),
                p.path.display()
            )));
        }
        if h.end > next {
            next = h.end;
            prev = Some(p);
        }
    }
    if next < n {
        return Err(Failure::from(format!(
            "items {next} to {} of {n} are missing: no part holds them",
            n - 1
        )));
    }
    // empty parts (more shards than items) are harmless, but the same part twice is not
    for w in parts.windows(2) {
        let (a, b) = (&w[0].header, &w[1].header);
        if a.start == a.end && a.shard == b.shard && a.shards == b.shards && a.start == b.start {
            return Err(Failure::from(format!(
                "shard {} of {} is given twice: {} and {}",
                a.shard,
                a.shards,
                w[0].path.display(),
                w[1].path.display()
            )));
        }
    }
    Ok(())
}

/// A reader of part `p`'s body from byte `offset` on.
pub(super) fn reader(p: &Part, offset: u64) -> Result<BufReader<File>, String> {
    let mut f = File::open(&p.path).map_err(|e| format!("{}: {e}", p.path.display()))?;
    f.seek(SeekFrom::Start(p.body_offset + offset))
        .map_err(|e| format!("{}: {e}", p.path.display()))?;
    Ok(BufReader::with_capacity(1 << 16, f))
}

/// Byte offset of section `k` in part `p`'s body.
pub(super) fn section_offset(p: &Part, k: usize) -> u64 {
    p.header.sections[..k].iter().sum()
}

/// The whole section `k` of part `p` (a small one: a stored nominal part, a study's base).
pub(super) fn read_section(p: &Part, k: usize) -> Result<Vec<u8>, String> {
    let mut b = vec![0u8; p.header.sections[k] as usize];
    reader(p, section_offset(p, k))?
        .read_exact(&mut b)
        .map_err(|e| format!("{}: {e}", p.path.display()))?;
    Ok(b)
}

/// Checks that every part has `n` sections, the first of `record` bytes per item when given.
pub(super) fn check_sections(parts: &[Part], n: usize, record: Option<u64>) -> Result<(), String> {
    for p in parts {
        let h = &p.header;
        let records_ok =
            record.is_none_or(|b| h.sections.first() == Some(&((h.end - h.start) * b)));
        if h.sections.len() != n || !records_ok {
            return Err(format!(
                "{}: the part's sections do not fit its request (damaged, or written by another \
                 build)",
                p.path.display()
            ));
        }
    }
    Ok(())
}

/// The part of shard 0, which carries what is not an item (`what`).
pub(super) fn part_zero<'a>(parts: &'a [Part], what: &str) -> Result<&'a Part, String> {
    parts.iter().find(|p| p.header.shard == 0).ok_or_else(|| {
        format!(
            "part 0 (shard 0 of {}) is missing: it carries {what}; compute shard 0 too",
            parts[0].header.shards
        )
    })
}

/// The values at the 0-based `ranks` (ascending) of the column made of section `section` of
/// every part (each sorted by `f64::total_cmp`): one reader per part, merged through a heap, so
/// O(parts) memory.
pub(super) fn merged_order_values(
    parts: &[Part],
    section: usize,
    ranks: &[u64],
) -> Result<Vec<f64>, String> {
    let mut readers = Vec::with_capacity(parts.len());
    let mut left = Vec::with_capacity(parts.len());
    let mut heap = BinaryHeap::with_capacity(parts.len());
    let read = |r: &mut BufReader<File>, p: &Part| -> Result<f64, String> {
        let mut b = [0u8; 8];
        r.read_exact(&mut b)
            .map_err(|e| format!("{}: {e}", p.path.display()))?;
        Ok(f64::from_le_bytes(b))
    };
    for (k, p) in parts.iter().enumerate() {
        let mut r = reader(p, section_offset(p, section))?;
        let count = p.header.sections[section] / 8;
        if count > 0 {
            heap.push(Next(read(&mut r, p)?, k));
        }
        readers.push(r);
        left.push(count.saturating_sub(1));
    }
    let mut out = Vec::with_capacity(ranks.len());
    let mut want = ranks.iter().peekable();
    let mut rank = 0u64;
    while let Some(&&w) = want.peek() {
        let Next(x, k) = heap
            .pop()
            .ok_or_else(|| format!("section {section} has fewer than {} values", w + 1))?;
        while want.peek() == Some(&&rank) {
            out.push(x);
            want.next();
        }
        rank += 1;
        if left[k] > 0 {
            left[k] -= 1;
            heap.push(Next(read(&mut readers[k], &parts[k])?, k));
        }
    }
    Ok(out)
}

/// The run records of a migration's parts (sorted by start, tiling 0..N).
pub(super) struct PartRuns<'a>(pub(super) &'a [Part]);

/// A key ordered by `f64::total_cmp`, smallest first in a max-heap.
pub(super) struct Next(f64, usize);

impl PartialEq for Next {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == std::cmp::Ordering::Equal
    }
}
impl Eq for Next {}
impl PartialOrd for Next {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Next {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}

impl RunRecords for PartRuns<'_> {
    type Error = String;

    fn runs(&self) -> u64 {
        self.0.first().map_or(0, |p| p.header.items)
    }

    fn for_each_run(&self, f: &mut dyn FnMut(&RunSummary)) -> Result<(), String> {
        let mut buf = [0u8; RUN_RECORD_BYTES as usize];
        for p in self.0 {
            let mut r = reader(p, 0)?;
            for _ in p.header.start..p.header.end {
                r.read_exact(&mut buf)
                    .map_err(|e| format!("{}: {e}", p.path.display()))?;
                f(&decode_run(&buf).map_err(|e| format!("{}: {e}", p.path.display()))?);
            }
        }
        Ok(())
    }

    fn order_values(&self, col: usize, ranks: &[u64]) -> Result<Vec<f64>, String> {
        merged_order_values(self.0, col + 1, ranks)
    }
}

/// The run records of one method of a scene's parts (sorted by start, tiling 0..N): its records
/// in section `first`, then five sorted columns per support entry (the runs that struck it
/// within capacity), then five design-value columns per entry (the runs that reached it).
pub(super) struct SceneRuns<'a> {
    pub(super) parts: &'a [Part],
    pub(super) first: usize,
    pub(super) limits: usize,
    /// Number of support entries.
    pub(super) entries: usize,
}

impl SceneRecords for SceneRuns<'_> {
    type Error = String;

    fn runs(&self) -> u64 {
        self.parts.first().map_or(0, |p| p.header.items)
    }

    fn for_each_run(&self, f: &mut dyn FnMut(&SceneRun)) -> Result<(), String> {
        let mut buf = [0u8; SCENE_RECORD_BYTES as usize];
        for p in self.parts {
            let mut r = reader(p, section_offset(p, self.first))?;
            for _ in p.header.start..p.header.end {
                r.read_exact(&mut buf)
                    .map_err(|e| format!("{}: {e}", p.path.display()))?;
                f(&decode_scene_run(&buf, self.limits)
                    .map_err(|e| format!("{}: {e}", p.path.display()))?);
            }
        }
        Ok(())
    }

    fn order_values(&self, entry: usize, col: usize, ranks: &[u64]) -> Result<Vec<f64>, String> {
        merged_order_values(
            self.parts,
            self.first + 1 + entry * ENTRY_COLUMNS + col,
            ranks,
        )
    }

    fn reach_order_values(
        &self,
        entry: usize,
        col: usize,
        ranks: &[u64],
    ) -> Result<Vec<f64>, String> {
        let entries = self.entries;
        merged_order_values(
            self.parts,
            self.first + 1 + entries * ENTRY_COLUMNS + entry * REACH_COLUMNS + col,
            ranks,
        )
    }
}

pub(super) fn read_u64(r: &mut BufReader<File>, p: &Part) -> Result<u64, String> {
    let mut b = [0u8; 8];
    r.read_exact(&mut b)
        .map_err(|e| format!("{}: {e}", p.path.display()))?;
    Ok(u64::from_le_bytes(b))
}
