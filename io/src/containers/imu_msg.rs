//! Decoding one `sensor_msgs/Imu` message payload: the ROS 1 serialisation and the ROS 2 CDR
//! encoding. Both are fixed layouts, read here field by field with bounds checks (no
//! allocation: `frame_id` is skipped, not copied).
//!
//! The message (ROS 1 `sensor_msgs/Imu`, ROS 2 `sensor_msgs/msg/Imu`):
//!
//! ```text
//! std_msgs/Header header                 ROS 1: uint32 seq, time stamp (uint32 sec, uint32 nsec), string frame_id
//!                                        ROS 2: builtin_interfaces/Time stamp (int32 sec, uint32 nanosec), string frame_id
//! geometry_msgs/Quaternion orientation   4 × float64
//! float64[9] orientation_covariance
//! geometry_msgs/Vector3 angular_velocity 3 × float64 [rad/s]
//! float64[9] angular_velocity_covariance
//! geometry_msgs/Vector3 linear_acceleration 3 × float64 [m/s²]
//! float64[9] linear_acceleration_covariance
//! ```
//!
//! ROS 1 (wiki.ros.org/msg, "Serialization"): little-endian, no padding, strings as a `uint32`
//! length then the bytes. ROS 2 (OMG CDR, XCDR version 1, as written by Fast DDS and Cyclone
//! DDS): a 4-byte encapsulation header (`00 00` big-endian or `00 01` little-endian, then two
//! option bytes), then the fields, each primitive aligned to its size counted from the end of
//! the encapsulation header; strings as a `uint32` length that counts the terminating NUL.

/// The fields of a `sensor_msgs/Imu` message this crate uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ImuMsg {
    /// `header.stamp` \[ns since the epoch of the recording's clock\].
    pub stamp_ns: i64,
    /// `angular_velocity` \[rad/s\], sensor frame.
    pub gyro: [f64; 3],
    /// `linear_acceleration` (specific force) \[m/s²\], sensor frame.
    pub accel: [f64; 3],
}

/// How a message payload is encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Encoding {
    /// ROS 1 serialisation (bags; MCAP with message encoding `ros1`).
    Ros1,
    /// ROS 2 CDR (MCAP with message encoding `cdr`).
    Cdr,
}

impl Encoding {
    /// Decodes `payload`.
    pub fn decode(self, payload: &[u8]) -> Result<ImuMsg, String> {
        match self {
            Encoding::Ros1 => decode_ros1(payload),
            Encoding::Cdr => decode_cdr(payload),
        }
    }
}

/// Nanoseconds per second.
const NS_PER_S: i64 = 1_000_000_000;

/// A bounds-checked reader of a byte slice with alignment relative to `origin`.
struct Bytes<'a> {
    data: &'a [u8],
    pos: usize,
    origin: usize,
    big_endian: bool,
    align: bool,
}

impl<'a> Bytes<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.data.len());
        let end = end.ok_or_else(|| {
            format!(
                "sensor_msgs/Imu payload of {} bytes ends inside {what} (needs {} more)",
                self.data.len(),
                (self.pos + n).saturating_sub(self.data.len())
            )
        })?;
        let out = &self.data[self.pos..end];
        self.pos = end;
        Ok(out)
    }

    fn align_to(&mut self, n: usize, what: &str) -> Result<(), String> {
        if self.align {
            let rel = self.pos - self.origin;
            let pad = (n - rel % n) % n;
            self.take(pad, what)?;
        }
        Ok(())
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        self.align_to(4, what)?;
        let b: [u8; 4] = self
            .take(4, what)?
            .try_into()
            .map_err(|_| what.to_string())?;
        Ok(if self.big_endian {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        })
    }

    fn f64s<const N: usize>(&mut self, what: &str) -> Result<[f64; N], String> {
        self.align_to(8, what)?;
        let mut out = [0.0; N];
        for v in &mut out {
            let b: [u8; 8] = self
                .take(8, what)?
                .try_into()
                .map_err(|_| what.to_string())?;
            *v = if self.big_endian {
                f64::from_be_bytes(b)
            } else {
                f64::from_le_bytes(b)
            };
        }
        Ok(out)
    }

    fn skip_string(&mut self) -> Result<(), String> {
        let len = self.u32("header.frame_id length")? as usize;
        self.take(len, "header.frame_id").map(|_| ())
    }

    /// Everything after `header`: returns (angular_velocity, linear_acceleration).
    fn body(&mut self) -> Result<([f64; 3], [f64; 3]), String> {
        self.f64s::<4>("orientation")?;
        self.f64s::<9>("orientation_covariance")?;
        let gyro = self.f64s::<3>("angular_velocity")?;
        self.f64s::<9>("angular_velocity_covariance")?;
        let accel = self.f64s::<3>("linear_acceleration")?;
        self.f64s::<9>("linear_acceleration_covariance")?;
        Ok((gyro, accel))
    }
}

fn stamp_ns(sec: i64, nsec: u32) -> Result<i64, String> {
    if i64::from(nsec) >= NS_PER_S {
        return Err(format!(
            "header.stamp has {nsec} ns in its nanoseconds field (must be < 10^9)"
        ));
    }
    Ok(sec * NS_PER_S + i64::from(nsec))
}

/// Decodes a ROS 1 serialised `sensor_msgs/Imu`.
pub(crate) fn decode_ros1(payload: &[u8]) -> Result<ImuMsg, String> {
    let mut b = Bytes {
        data: payload,
        pos: 0,
        origin: 0,
        big_endian: false,
        align: false,
    };
    b.u32("header.seq")?;
    let sec = b.u32("header.stamp.secs")?;
    let nsec = b.u32("header.stamp.nsecs")?;
    b.skip_string()?;
    let (gyro, accel) = b.body()?;
    Ok(ImuMsg {
        stamp_ns: stamp_ns(i64::from(sec), nsec)?,
        gyro,
        accel,
    })
}

/// Decodes a ROS 2 CDR encoded `sensor_msgs/msg/Imu`.
pub(crate) fn decode_cdr(payload: &[u8]) -> Result<ImuMsg, String> {
    let big_endian = match payload.get(..2) {
        Some([0, 0]) => true,
        Some([0, 1]) => false,
        Some(id) => {
            return Err(format!(
                "unsupported CDR encapsulation {:02x}{:02x} (expected plain CDR: 0000 or 0001)",
                id[0], id[1]
            ));
        }
        None => return Err("CDR payload shorter than its 4-byte encapsulation header".into()),
    };
    let mut b = Bytes {
        data: payload,
        pos: 0,
        origin: 4,
        big_endian,
        align: true,
    };
    b.take(4, "the CDR encapsulation header")?;
    let sec = b.u32("header.stamp.sec")? as i32;
    let nsec = b.u32("header.stamp.nanosec")?;
    b.skip_string()?;
    let (gyro, accel) = b.body()?;
    Ok(ImuMsg {
        stamp_ns: stamp_ns(i64::from(sec), nsec)?,
        gyro,
        accel,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ROS 1 message built field by field (layout from the ROS 1 serialisation rules).
    fn ros1_bytes(frame: &str) -> Vec<u8> {
        let mut v = Vec::new();
        v.extend(7u32.to_le_bytes());
        v.extend(12u32.to_le_bytes());
        v.extend(345u32.to_le_bytes());
        v.extend((frame.len() as u32).to_le_bytes());
        v.extend(frame.as_bytes());
        for i in 0..37 {
            v.extend((i as f64 + 0.5).to_le_bytes());
        }
        v
    }

    #[test]
    fn ros1_fields_at_their_offsets() {
        let m = decode_ros1(&ros1_bytes("imu")).unwrap();
        assert_eq!(m.stamp_ns, 12_000_000_345);
        // orientation 0..4, covariance 4..13, angular velocity 13..16.
        assert_eq!(m.gyro, [13.5, 14.5, 15.5]);
        assert_eq!(m.accel, [25.5, 26.5, 27.5]);
    }

    #[test]
    fn ros1_truncated_is_an_error() {
        let b = ros1_bytes("imu");
        for n in [0, 3, 15, b.len() - 1] {
            assert!(decode_ros1(&b[..n]).is_err(), "{n} bytes");
        }
        let mut long_frame = ros1_bytes("");
        long_frame[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode_ros1(&long_frame).unwrap_err().contains("frame_id"));
    }

    /// A CDR message built field by field: frame "ab" (length 3 with NUL) ends at body offset
    /// 15, so `orientation` is padded to body offset 16.
    fn cdr_bytes(big_endian: bool) -> Vec<u8> {
        let u32b = |x: u32| {
            if big_endian {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            }
        };
        let mut v = vec![0, u8::from(!big_endian), 0, 0];
        v.extend(u32b((-2i32) as u32));
        v.extend(u32b(5));
        v.extend(u32b(3));
        v.extend(b"ab\0");
        v.push(0); // padding to 8
        for i in 0..37 {
            let x = i as f64 - 0.25;
            v.extend(if big_endian {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            });
        }
        v
    }

    #[test]
    fn cdr_both_endiannesses() {
        for be in [false, true] {
            let m = decode_cdr(&cdr_bytes(be)).unwrap();
            assert_eq!(m.stamp_ns, -2_000_000_000 + 5);
            assert_eq!(m.gyro, [12.75, 13.75, 14.75]);
            assert_eq!(m.accel, [24.75, 25.75, 26.75]);
        }
    }

    #[test]
    fn cdr_bad_encapsulation_and_truncation() {
        let mut b = cdr_bytes(false);
        b[1] = 7;
        assert!(decode_cdr(&b).unwrap_err().contains("encapsulation"));
        let b = cdr_bytes(false);
        assert!(decode_cdr(&b[..b.len() - 8]).is_err());
        assert!(decode_cdr(&b[..1]).is_err());
    }

    #[test]
    fn nanoseconds_out_of_range() {
        let mut b = ros1_bytes("");
        b[8..12].copy_from_slice(&1_000_000_000u32.to_le_bytes());
        assert!(decode_ros1(&b).unwrap_err().contains("10^9"));
    }
}
