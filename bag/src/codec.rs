//! Message payloads: ROS 1 serialisation (`roslibrust_serde_rosmsg`) and ROS 2 CDR
//! (`cdr-encoding`, with the 4-byte encapsulation header ROS 2 puts first).

use byteorder::{BigEndian, LittleEndian};

use crate::msg::Message;

/// How a message's bytes are serialised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// ROS 1 serialisation (a ROS 1 bag, or an MCAP channel with encoding `ros1`).
    Ros1,
    /// OMG CDR with the encapsulation header (ROS 2; MCAP encoding `cdr`).
    Cdr,
}

impl Encoding {
    /// The MCAP `message_encoding` name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ros1 => "ros1",
            Self::Cdr => "cdr",
        }
    }
}

/// CDR encapsulation identifiers (OMG DDS-XTypes 7.6.3.1.2): plain CDR, big or little endian.
const CDR_BE: [u8; 2] = [0x00, 0x00];
const CDR_LE: [u8; 2] = [0x00, 0x01];

/// Decodes `bytes` as a `T` in `encoding`. Every byte must be used, but for up to 3 bytes of
/// CDR's final alignment padding.
///
/// # Errors
/// A description of what did not decode (wrapped by the callers with the topic and index).
pub fn decode<T: Message>(encoding: Encoding, bytes: &[u8]) -> Result<T, String> {
    match encoding {
        Encoding::Ros1 => {
            let len = u32::try_from(bytes.len()).map_err(|_| "message over 4 GiB".to_owned())?;
            roslibrust_serde_rosmsg::from_slice_known_length::<T::Ros1>(bytes, len)
                .map(T::from_ros1)
                .map_err(|e| format!("ROS 1 decoding: {e}"))
        }
        Encoding::Cdr => {
            let (head, body) = bytes
                .split_at_checked(4)
                .ok_or_else(|| format!("CDR message of {} bytes has no header", bytes.len()))?;
            let (value, used) = match [head[0], head[1]] {
                CDR_LE => cdr_encoding::from_bytes::<T, LittleEndian>(body),
                CDR_BE => cdr_encoding::from_bytes::<T, BigEndian>(body),
                other => {
                    return Err(format!(
                        "CDR encapsulation {other:02x?} is not plain CDR (XCDR is not supported)"
                    ));
                }
            }
            .map_err(|e| format!("CDR decoding: {e}"))?;
            let left = body.len().saturating_sub(used);
            if left > 3 {
                return Err(format!(
                    "CDR decoding used {used} of {} bytes: the data does not match the type",
                    body.len()
                ));
            }
            Ok(value)
        }
    }
}

/// Encodes `message` as ROS 2 CDR, little endian, with its encapsulation header.
///
/// # Errors
/// A description of what did not encode.
pub fn encode_cdr<T: Message>(message: &T) -> Result<Vec<u8>, String> {
    let body = cdr_encoding::to_vec::<T, LittleEndian>(message).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(body.len() + 4);
    out.extend_from_slice(&CDR_LE);
    out.extend_from_slice(&[0, 0]);
    out.extend_from_slice(&body);
    Ok(out)
}

/// Encodes `message` in ROS 1 serialisation (without the 4-byte length prefix of the wire).
///
/// # Errors
/// A description of what did not encode.
pub fn encode_ros1<T: Message>(message: &T) -> Result<Vec<u8>, String> {
    roslibrust_serde_rosmsg::to_vec_skip_length(&message.to_ros1()).map_err(|e| e.to_string())
}
