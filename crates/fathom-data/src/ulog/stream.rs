//! Streaming extraction of chosen topics and fields from a ULog byte stream, on PX4's
//! `px4-ulog` parser: the bytes are fed in chunks of [`CHUNK_BYTES`], each data
//! message of a requested topic (instance 0) is decoded into `f64`s and handed to a
//! sink, and nothing else is kept; a 1 GB log is never held in memory.
//!
//! The framing is fathom's: after the 16-byte header, each message (`u16` size,
//! type, payload) is cut from the stream, checked for what `px4-ulog` 0.6.1 indexes
//! without checking (`check_message`: fuzzing found panics there), and fed to the
//! parser alone; a panic the check does not foresee is caught and becomes an error.
//! Strict where the `px4-ulog` drivers are lenient: a file that ends inside a message
//! ([`UlogError::Truncated`]) or holds a message that does not decode
//! ([`UlogError::Malformed`], with the message's byte range) is an error, not a
//! shorter flight. Appended-data sections (the `FlagBits` offsets) are read in file
//! order, a message cut by a section start dropped, as PX4's readers do.

use std::cell::Cell;
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use px4_ulog::stream_parser::LogParser;
use px4_ulog::stream_parser::model::{DataMessage, FlattenedFieldType};

use super::error::UlogError;

/// Length of the ULog file header (magic, version, time stamp), bytes.
const HEADER_BYTES: u64 = 16;

/// Bytes read and fed to the parser at a time.
pub const CHUNK_BYTES: usize = 64 * 1024;

/// One field to read, by its flattened name (`accelerometer_m_s2[0]`), with the
/// alternative names of other PX4 versions (`lat` / `latitude_deg`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldRequest {
    /// Accepted names, first match wins.
    pub names: &'static [&'static str],
    /// Whether a topic without it is an error (otherwise the value is NaN).
    pub required: bool,
}

impl FieldRequest {
    /// A required field.
    pub const fn required(names: &'static [&'static str]) -> Self {
        Self {
            names,
            required: true,
        }
    }

    /// An optional field (NaN when absent).
    pub const fn optional(names: &'static [&'static str]) -> Self {
        Self {
            names,
            required: false,
        }
    }
}

/// One topic to read and its fields, in the order of [`Sample::values`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TopicRequest {
    /// The topic (`sensor_combined`).
    pub topic: &'static str,
    /// The fields.
    pub fields: &'static [FieldRequest],
}

/// One decoded message of a requested topic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample<'a> {
    /// Index of the topic in the request list.
    pub request: usize,
    /// The message's `timestamp`, microseconds since boot.
    pub time_us: u64,
    /// The requested fields as `f64` (integers exactly up to 2^53; NaN for an absent
    /// optional field).
    pub values: &'a [f64],
}

/// How a field is read from a message's bytes.
#[derive(Debug, Clone, Copy)]
struct Accessor {
    offset: usize,
    ty: Scalar,
}

#[derive(Debug, Clone, Copy)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
    Bool,
    Absent,
}

fn scalar(t: &FlattenedFieldType) -> Option<Scalar> {
    Some(match t {
        FlattenedFieldType::Int8 => Scalar::I8,
        FlattenedFieldType::UInt8 => Scalar::U8,
        FlattenedFieldType::Int16 => Scalar::I16,
        FlattenedFieldType::UInt16 => Scalar::U16,
        FlattenedFieldType::Int32 => Scalar::I32,
        FlattenedFieldType::UInt32 => Scalar::U32,
        FlattenedFieldType::Int64 => Scalar::I64,
        FlattenedFieldType::UInt64 => Scalar::U64,
        FlattenedFieldType::Float => Scalar::F32,
        FlattenedFieldType::Double => Scalar::F64,
        FlattenedFieldType::Bool => Scalar::Bool,
        FlattenedFieldType::Char => return None,
    })
}

fn bytes<const N: usize>(data: &[u8], offset: usize) -> Option<[u8; N]> {
    data.get(offset..offset.checked_add(N)?)?.try_into().ok()
}

impl Accessor {
    /// The value in `data` (the message with its msg_id); NaN when out of bounds.
    fn read(&self, data: &[u8]) -> f64 {
        let o = self.offset;
        let v = match self.ty {
            Scalar::I8 => bytes::<1>(data, o).map(|b| f64::from(i8::from_le_bytes(b))),
            Scalar::U8 => bytes::<1>(data, o).map(|b| f64::from(b[0])),
            Scalar::Bool => bytes::<1>(data, o).map(|b| f64::from(u8::from(b[0] != 0))),
            Scalar::I16 => bytes::<2>(data, o).map(|b| f64::from(i16::from_le_bytes(b))),
            Scalar::U16 => bytes::<2>(data, o).map(|b| f64::from(u16::from_le_bytes(b))),
            Scalar::I32 => bytes::<4>(data, o).map(|b| f64::from(i32::from_le_bytes(b))),
            Scalar::U32 => bytes::<4>(data, o).map(|b| f64::from(u32::from_le_bytes(b))),
            // 64-bit integers: exact up to 2^53 (time stamps, counters)
            Scalar::I64 => bytes::<8>(data, o).map(|b| i64::from_le_bytes(b) as f64),
            Scalar::U64 => bytes::<8>(data, o).map(|b| u64::from_le_bytes(b) as f64),
            Scalar::F32 => bytes::<4>(data, o).map(|b| f64::from(f32::from_le_bytes(b))),
            Scalar::F64 => bytes::<8>(data, o).map(f64::from_le_bytes),
            Scalar::Absent => None,
        };
        v.unwrap_or(f64::NAN)
    }
}

/// The layout of one msg_id: which request it serves and how to read its fields
/// (`None`: a topic not requested, or instance > 0).
type Layout = Option<(usize, usize, Vec<Accessor>)>;

/// What the data callback collects.
struct State<'s> {
    requests: &'s [TopicRequest],
    layouts: HashMap<u16, Layout>,
    values: Vec<f64>,
    sink: &'s mut dyn FnMut(&Sample<'_>) -> Result<(), UlogError>,
    error: Option<UlogError>,
    failed: &'s Cell<bool>,
    path: &'s Path,
}

impl State<'_> {
    fn layout(&self, msg: &DataMessage<'_>) -> Result<Layout, UlogError> {
        if msg.multi_id.value() != 0 {
            return Ok(None);
        }
        let fmt = msg.flattened_format;
        let Some(request) = self
            .requests
            .iter()
            .position(|r| r.topic == fmt.message_name())
        else {
            return Ok(None);
        };
        let field = |name: &str| fmt.field_iter().find(|f| f.flattened_field_name == name);
        let Some(ts) = field("timestamp").filter(|f| f.field_type == FlattenedFieldType::UInt64)
        else {
            return Err(UlogError::FieldMissing {
                path: self.path.to_path_buf(),
                topic: fmt.message_name().to_string(),
                field: "timestamp".into(),
            });
        };
        let mut acc = Vec::with_capacity(self.requests[request].fields.len());
        for fr in self.requests[request].fields {
            let found = fr
                .names
                .iter()
                .find_map(|n| field(n).and_then(|f| Some((f.offset, scalar(&f.field_type)?))));
            match found {
                Some((offset, ty)) => acc.push(Accessor {
                    offset: usize::from(offset),
                    ty,
                }),
                None if fr.required => {
                    return Err(UlogError::FieldMissing {
                        path: self.path.to_path_buf(),
                        topic: fmt.message_name().to_string(),
                        field: fr.names.join("` or `"),
                    });
                }
                None => acc.push(Accessor {
                    offset: 0,
                    ty: Scalar::Absent,
                }),
            }
        }
        Ok(Some((request, usize::from(ts.offset), acc)))
    }

    fn on_data(&mut self, msg: &DataMessage<'_>) {
        if self.error.is_some() {
            return;
        }
        if let Err(e) = self.try_data(msg) {
            self.error = Some(e);
            self.failed.set(true);
        }
    }

    fn try_data(&mut self, msg: &DataMessage<'_>) -> Result<(), UlogError> {
        if !self.layouts.contains_key(&msg.msg_id) {
            let l = self.layout(msg)?;
            self.layouts.insert(msg.msg_id, l);
        }
        let Some(Some((request, ts, acc))) = self.layouts.get(&msg.msg_id) else {
            return Ok(());
        };
        let Some(time) = bytes::<8>(msg.data, *ts).map(u64::from_le_bytes) else {
            return Ok(());
        };
        self.values.clear();
        self.values.extend(acc.iter().map(|a| a.read(msg.data)));
        let sample = Sample {
            request: *request,
            time_us: time,
            values: &self.values,
        };
        (self.sink)(&sample)
    }
}

/// Streams `reader` (the ULog file `path`, which labels errors) and hands every
/// message of a requested topic to `sink` in file order. Returns the bytes read.
///
/// # Errors
/// [`UlogError::Empty`], [`UlogError::Truncated`], [`UlogError::Malformed`],
/// [`UlogError::FieldMissing`], [`UlogError::Io`], or the sink's error.
pub fn stream_topics(
    mut reader: impl Read,
    path: &Path,
    requests: &[TopicRequest],
    sink: &mut dyn FnMut(&Sample<'_>) -> Result<(), UlogError>,
) -> Result<u64, UlogError> {
    let io = |source| UlogError::Io {
        path: path.to_path_buf(),
        source,
    };
    let failed = Cell::new(false);
    let mut state = State {
        requests,
        layouts: HashMap::new(),
        values: Vec::new(),
        sink,
        error: None,
        failed: &failed,
        path,
    };
    let mut on_data = |m: &DataMessage<'_>| state.on_data(m);
    let mut parser = LogParser::default();
    parser.set_data_message_callback(&mut on_data);
    let malformed = |start: u64, end: u64, reason: String| UlogError::Malformed {
        path: path.to_path_buf(),
        start,
        end,
        reason,
    };
    // The 16-byte file header, then one whole message at a time (own framing: each
    // message is checked by `check_message` before the parser sees it).
    let mut header = [0u8; HEADER_BYTES as usize];
    let mut got = 0;
    while got < header.len() {
        let n = read_some(&mut reader, &mut header[got..]).map_err(io)?;
        if n == 0 {
            return Err(if got == 0 {
                UlogError::Empty {
                    path: path.to_path_buf(),
                }
            } else {
                UlogError::Truncated {
                    path: path.to_path_buf(),
                    len: got as u64,
                    what: "header",
                }
            });
        }
        got += n;
    }
    feed(&mut parser, &header).map_err(|r| malformed(0, HEADER_BYTES, r))?;
    let mut pos: u64 = HEADER_BYTES; // file offset of buf[start]
    let mut buf: Vec<u8> = Vec::with_capacity(2 * CHUNK_BYTES);
    let mut start = 0usize;
    let mut chunk = vec![0u8; CHUNK_BYTES];
    // appended-data section starts ahead, the nearest last (known after FlagBits)
    let mut sections: Option<Vec<u64>> = None;
    let mut eof = false;
    loop {
        let avail = &buf[start..];
        if avail.len() >= 3 {
            let total = 3 + usize::from(u16::from_le_bytes([avail[0], avail[1]]));
            if avail.len() >= total {
                let end = pos + total as u64;
                let next = sections.as_ref().and_then(|s| s.last().copied());
                if let Some(b) = next
                    && b < end
                {
                    // a message cut by an appended section: drop its head
                    let skip = usize::try_from(b.saturating_sub(pos)).unwrap_or(total);
                    start += skip;
                    pos += skip as u64;
                    if let Some(s) = sections.as_mut() {
                        s.pop();
                    }
                    continue;
                }
                let msg = &avail[..total];
                check_message(msg).map_err(|r| malformed(pos, end, r))?;
                feed(&mut parser, msg).map_err(|r| malformed(pos, end, r))?;
                start += total;
                pos = end;
                if failed.get() {
                    break;
                }
                if sections.is_none() && parser.header_complete() {
                    let mut s: Vec<u64> = parser
                        .appended_offsets()
                        .iter()
                        .copied()
                        .filter(|&o| o > pos)
                        .collect();
                    s.sort_unstable_by(|a, b| b.cmp(a));
                    sections = Some(s);
                }
                continue;
            }
        }
        if eof {
            break;
        }
        buf.drain(..start);
        start = 0;
        let n = read_some(&mut reader, &mut chunk).map_err(io)?;
        if n == 0 {
            eof = true;
        } else {
            buf.extend_from_slice(&chunk[..n]);
        }
    }
    let leftover = (buf.len() - start) as u64;
    drop(parser);
    if let Some(e) = state.error {
        return Err(e);
    }
    if leftover > 0 {
        return Err(UlogError::Truncated {
            path: path.to_path_buf(),
            len: pos + leftover,
            what: "message",
        });
    }
    Ok(pos)
}

/// Feeds `bytes` (the header, or exactly one message) to the parser; a panic inside
/// the parser (a malformed message `check_message` does not know) is caught and
/// returned as an error, so that no input crashes fathom.
fn feed(parser: &mut LogParser<'_>, bytes: &[u8]) -> Result<(), String> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| parser.consume_bytes(bytes))) {
        Ok(Ok(())) => Ok(()),
        Ok(Err(e)) => Err(e.description),
        Err(_) => Err("the ULog parser failed on this message".into()),
    }
}

/// Checks what `px4-ulog` 0.6.1 indexes without checking (found by fuzzing: it
/// panicked on them): a parameter message's key length within the message, an
/// add-logged message of at least 3 bytes.
fn check_message(msg: &[u8]) -> Result<(), String> {
    let payload = &msg[3..];
    match msg[2] {
        b'P' => match payload.first() {
            Some(&k) if payload.len() > usize::from(k) => Ok(()),
            _ => Err(format!(
                "parameter message of {} bytes shorter than its key length",
                payload.len()
            )),
        },
        b'A' if payload.len() < 3 => Err(format!(
            "add-logged message of {} bytes, fewer than 3",
            payload.len()
        )),
        _ => Ok(()),
    }
}

/// `read` retried on `Interrupted`.
fn read_some(reader: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    loop {
        match reader.read(buf) {
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            r => return r,
        }
    }
}
