//! The firmware's defmt stream, decoded by type: every message is a name and `key={=type}`
//! fields (`ssvr_proto::stream`); `defmt-decoder` gives each field's type from the interned
//! format string and its value on its own, so a field is read by its key and type, never by
//! parsing the message's text. The frames come out as `ssvr_proto::Frame`s ([`frames`]).

use anyhow::{anyhow, bail, Context, Result};
use defmt_parser::{Fragment, Type};
use ssvr_proto::stream::{EVENT_FIELDS, FRAME, FRAME_FIELDS};
use ssvr_proto::{Event, EventKind, Frame};
use std::path::Path;

/// A typed field value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// An unsigned integer (`u8` .. `u64`).
    Uint(u64),
    /// A signed integer (`i8` .. `i64`).
    Int(i64),
    /// An `f32`.
    F32(f32),
    /// An `f64`.
    F64(f64),
    /// A `bool`.
    Bool(bool),
    /// Anything else, as displayed (strings, byte slices, `Format` values).
    Text(String),
}

/// One decoded message.
#[derive(Debug, Clone, PartialEq)]
pub struct Message {
    /// Log level (`"info"`, `"error"`, ...), `None` for `println!`-style frames.
    pub level: Option<String>,
    /// The message's name: its first word (`sample`, `icount`, `stats`, `plan`, `mu`, ...).
    pub name: String,
    /// The literal words between the name and the first field (e.g. `raw` in `icount raw ..`).
    pub topic: String,
    /// The fields, in order: (key, value).
    pub fields: Vec<(String, Value)>,
    /// The whole message as displayed (for people).
    pub text: String,
}

impl std::fmt::Display for Message {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.level {
            Some(l) => write!(f, "{l:>5} {}", self.text),
            None => write!(f, "{}", self.text),
        }
    }
}

impl Message {
    /// The value of field `key`.
    pub fn get(&self, key: &str) -> Option<&Value> {
        self.fields.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }

    /// An unsigned integer field.
    pub fn uint(&self, key: &str) -> Option<u64> {
        match self.get(key)? {
            Value::Uint(v) => Some(*v),
            _ => None,
        }
    }

    /// A `u32` field.
    pub fn u32(&self, key: &str) -> Option<u32> {
        self.uint(key).and_then(|v| u32::try_from(v).ok())
    }

    /// A signed integer field.
    pub fn int(&self, key: &str) -> Option<i64> {
        match self.get(key)? {
            Value::Int(v) => Some(*v),
            _ => None,
        }
    }

    /// An `f32` field.
    pub fn f32(&self, key: &str) -> Option<f32> {
        match self.get(key)? {
            Value::F32(v) => Some(*v),
            _ => None,
        }
    }

    /// An `f64` field (an `f32` one widened).
    pub fn f64(&self, key: &str) -> Option<f64> {
        match self.get(key)? {
            Value::F64(v) => Some(*v),
            Value::F32(v) => Some(f64::from(*v)),
            _ => None,
        }
    }

    /// A `bool` field.
    pub fn bool(&self, key: &str) -> Option<bool> {
        match self.get(key)? {
            Value::Bool(v) => Some(*v),
            _ => None,
        }
    }

    /// Whether the message is `name` (and, if given, `topic`).
    pub fn is(&self, name: &str, topic: Option<&str>) -> bool {
        self.name == name && topic.is_none_or(|t| self.topic == t)
    }
}

fn value(ty: &Type, shown: &str) -> Value {
    let text = || Value::Text(shown.to_string());
    match ty {
        Type::U8 | Type::U16 | Type::U32 | Type::U64 | Type::Usize => {
            shown.parse().map_or_else(|_| text(), Value::Uint)
        }
        Type::I8 | Type::I16 | Type::I32 | Type::I64 | Type::Isize => {
            shown.parse().map_or_else(|_| text(), Value::Int)
        }
        Type::F32 => shown.parse().map_or_else(|_| text(), Value::F32),
        Type::F64 => shown.parse().map_or_else(|_| text(), Value::F64),
        Type::Bool => shown.parse().map_or_else(|_| text(), Value::Bool),
        _ => text(),
    }
}

/// A decoded defmt frame as a [`Message`] (its fields by key and type).
pub fn message(f: &defmt_decoder::Frame<'_>) -> Message {
    let mut literal = String::new();
    let mut fields = Vec::new();
    let mut head: Option<String> = None;
    for (frag, shown) in f.fragments().into_iter().zip(f.display_fragments()) {
        match frag {
            Fragment::Literal(l) => literal.push_str(&l),
            Fragment::Parameter(p) => {
                // The key is the last word of the literal before the field, without its `=`.
                let lit = std::mem::take(&mut literal);
                let (before, key) = match lit.trim_end().strip_suffix('=') {
                    Some(k) => match k.rsplit_once(char::is_whitespace) {
                        Some((b, key)) => (b.to_string(), key.to_string()),
                        None => (String::new(), k.to_string()),
                    },
                    None => (lit.clone(), String::new()),
                };
                if head.is_none() {
                    head = Some(before);
                }
                fields.push((key, value(&p.ty, &shown)));
            }
        }
    }
    let head = head.unwrap_or(literal);
    let mut words = head.split_whitespace();
    let name = words.next().unwrap_or("").to_string();
    let topic = words.collect::<Vec<_>>().join(" ");
    Message {
        level: f.level().map(|l| l.as_str().to_string()),
        name,
        topic,
        fields,
        text: f.display_message().to_string(),
    }
}

/// The defmt interning table of the ELF `elf` (errors name the file).
pub fn table(elf: &Path) -> Result<defmt_decoder::Table> {
    let image =
        std::fs::read(elf).with_context(|| format!("cannot read the ELF {}", elf.display()))?;
    defmt_decoder::Table::parse(&image)
        .with_context(|| format!("cannot read the defmt table of {}", elf.display()))?
        .ok_or_else(|| anyhow!("{} has no defmt data", elf.display()))
}

/// Decode a defmt byte stream with the interning table of `elf`.
pub fn decode(elf: &Path, bytes: &[u8]) -> Result<Vec<Message>> {
    let table = table(elf)?;
    let mut decoder = table.new_stream_decoder();
    let mut out = Vec::new();
    // Fed in chunks: the stream decoder drains its buffer from the front, which is quadratic in
    // the buffered length (a 320 000-frame stream took a minute in one piece).
    for chunk in bytes.chunks(4096) {
        decoder.received(chunk);
        loop {
            match decoder.decode() {
                Ok(f) => out.push(message(&f)),
                Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
                Err(defmt_decoder::DecodeError::Malformed) => {
                    if !table.encoding().can_recover() {
                        bail!(
                            "malformed defmt frame after {} messages (raw encoding)",
                            out.len()
                        );
                    }
                }
            }
        }
    }
    Ok(out)
}

/// A `sample` message as a frame (`None` for any other message or a malformed one).
pub fn frame(m: &Message) -> Option<Frame> {
    if m.name != FRAME {
        return None;
    }
    let [idx, flags, table, base, top, disp, pred] = FRAME_FIELDS;
    let event = match m.get(EVENT_FIELDS[0]) {
        None => None,
        Some(_) => {
            let [ev, level, age] = EVENT_FIELDS;
            Some(Event {
                kind: EventKind::from_code(u8::try_from(m.uint(ev)?).ok()?)?,
                level: i8::try_from(m.int(level)?).ok()?,
                age_samples: m.f32(age)?,
            })
        }
    };
    Some(Frame {
        index: m.u32(idx)?,
        flags: u8::try_from(m.uint(flags)?).ok()?,
        event,
        channels: [m.f32(table)?, m.f32(base)?, m.f32(top)?, m.f32(disp)?],
        prediction: m.f32(pred)?,
    })
}

/// The frames of a stream, in order; a malformed `sample` message is an error.
pub fn frames(messages: &[Message]) -> Result<Vec<Frame>> {
    messages
        .iter()
        .filter(|m| m.name == FRAME)
        .map(|m| frame(m).ok_or_else(|| anyhow!("malformed frame: {}", m.text)))
        .collect()
}

/// The plan the image reports: (digest, history).
pub fn plan_digest(messages: &[Message]) -> Option<u32> {
    messages
        .iter()
        .find(|m| m.name == ssvr_proto::stream::PLAN)?
        .u32("digest")
}

/// The firmware's `mu estimate=.. std=.. samples=..` message: (μ̂, std, identification updates).
pub fn mu(messages: &[Message]) -> Option<(f64, f64, u32)> {
    let m = messages
        .iter()
        .find(|m| m.name == "mu" && m.get("estimate").is_some())?;
    Some((m.f64("estimate")?, m.f64("std")?, m.u32("samples")?))
}

/// The firmware's last `law mu_slow=.. mu_fast=.. rate_s_m=.. adoptions=..` message: the
/// velocity-dependent friction law in use (μ_slow, μ_fast, a, adoptions).
pub fn law(messages: &[Message]) -> Option<(f32, f32, f32, u32)> {
    let m = messages.iter().rev().find(|m| m.name == "law")?;
    Some((
        m.f64("mu_slow")? as f32,
        m.f64("mu_fast")? as f32,
        m.f64("rate_s_m")? as f32,
        m.u32("adoptions")?,
    ))
}
