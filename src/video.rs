//! A sequence's frames as an MP4 video (H.264, what browsers and common players open), encoded
//! in the process: OpenH264 (the `openh264` crate, built from its source) makes the bitstream
//! and the `mp4` crate boxes it. No system tool is needed at run time.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use openh264::encoder::{
    Encoder, EncoderConfig, FrameRate, FrameType, IntraFramePeriod, RateControlMode, VuiConfig,
};
use openh264::formats::{RgbaSliceU8, YUVBuffer};

use crate::error::{Error, Result};

/// Ticks a second of the video track's clock (MPEG's 90 kHz).
const TIMESCALE: u32 = 90_000;

/// An MP4 file being written, a frame at a time.
pub struct VideoWriter {
    path: PathBuf,
    encoder: Encoder,
    width: u32,
    height: u32,
    /// Ticks a frame lasts.
    duration: u32,
    /// The MP4 writer, made at the first frame (its track needs the stream's parameter sets).
    mp4: Option<mp4::Mp4Writer<BufWriter<File>>>,
    /// Frames written.
    frames: u64,
}

fn failed(path: &Path, what: impl std::fmt::Display) -> Error {
    Error::Invalid(format!("{}: video: {what}", path.display()))
}

/// A NAL unit without its start code (00 00 01 or 00 00 00 01).
fn unprefixed(nal: &[u8]) -> &[u8] {
    let zeros = nal.iter().take_while(|&&b| b == 0).count();
    if zeros >= 2 && nal.get(zeros) == Some(&1) {
        &nal[zeros + 1..]
    } else {
        nal
    }
}

impl VideoWriter {
    /// Starts `path` for frames of `width` × `height` (even: 4:2:0 halves both) at `fps`.
    pub fn create(path: &Path, width: u32, height: u32, fps: f32) -> Result<VideoWriter> {
        if !width.is_multiple_of(2) || !height.is_multiple_of(2) {
            return Err(failed(
                path,
                format!("H.264 needs an even width and height, got {width}×{height}"),
            ));
        }
        if width > u16::MAX as u32 || height > u16::MAX as u32 {
            return Err(failed(path, format!("{width}×{height} is too large")));
        }
        crate::scene::path::check_fps(fps).map_err(|m| failed(path, m))?;
        let config = EncoderConfig::new()
            .max_frame_rate(FrameRate::from_hz(fps))
            // No rate control: OpenH264 meets a bit rate only by skipping frames, and a
            // sequence's every frame must be there. Its fixed quantizer (26) decodes a frame
            // within the PSNR `tests/video.rs` asserts of the PNG of the same view.
            .rate_control_mode(RateControlMode::Off)
            .skip_frames(false)
            .intra_frame_period(IntraFramePeriod::from_num_frames((2.0 * fps).ceil() as u32))
            // The RGB → YUV conversion below is BT.601's, studio range.
            .vui(VuiConfig::bt601());
        let api = openh264::OpenH264API::from_source();
        let encoder = Encoder::with_api_config(api, config).map_err(|e| failed(path, e))?;
        // Fail on an unwritable path before any frame is drawn.
        File::create(path).map_err(|e| Error::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        Ok(VideoWriter {
            path: path.to_path_buf(),
            encoder,
            width,
            height,
            duration: (TIMESCALE as f32 / fps).round() as u32,
            mp4: None,
            frames: 0,
        })
    }

    /// Encodes a frame: RGBA8 pixels (red in the low byte), rows from the top.
    pub fn push(&mut self, rgba: &[u32]) -> Result<()> {
        let (w, h) = (self.width as usize, self.height as usize);
        if rgba.len() != w * h {
            return Err(failed(
                &self.path,
                format!("a frame of {} pixels for {w}×{h}", rgba.len()),
            ));
        }
        let bytes: &[u8] = bytemuck::cast_slice(rgba);
        let yuv = YUVBuffer::from_rgba8_source(RgbaSliceU8::new(bytes, (w, h)));
        let path = self.path.clone();
        let stream = self.encoder.encode(&yuv).map_err(|e| failed(&path, e))?;
        let sync = matches!(stream.frame_type(), FrameType::IDR | FrameType::I);
        // The frame's NAL units, length-prefixed as MP4 holds them; the parameter sets go
        // to the track's header instead.
        let (mut sample, mut sps, mut pps) = (Vec::new(), None, None);
        for l in 0..stream.num_layers() {
            let Some(layer) = stream.layer(l) else {
                continue;
            };
            for n in 0..layer.nal_count() {
                let Some(nal) = layer.nal_unit(n).map(unprefixed) else {
                    continue;
                };
                match nal.first().map(|b| b & 0x1f) {
                    Some(7) => sps = Some(nal.to_vec()),
                    Some(8) => pps = Some(nal.to_vec()),
                    Some(_) => {
                        sample.extend_from_slice(&(nal.len() as u32).to_be_bytes());
                        sample.extend_from_slice(nal);
                    }
                    None => {}
                }
            }
        }
        if self.mp4.is_none() {
            let (Some(sps), Some(pps)) = (sps, pps) else {
                return Err(failed(&path, "the first frame carries no parameter sets"));
            };
            self.mp4 = Some(self.start(sps, pps)?);
        }
        let Some(mp4) = self.mp4.as_mut() else {
            return Err(failed(&path, "no track"));
        };
        let frame = mp4::Mp4Sample {
            start_time: self.frames * self.duration as u64,
            duration: self.duration,
            rendering_offset: 0,
            is_sync: sync,
            bytes: sample.into(),
        };
        mp4.write_sample(1, &frame).map_err(|e| failed(&path, e))?;
        self.frames += 1;
        Ok(())
    }

    fn start(&self, sps: Vec<u8>, pps: Vec<u8>) -> Result<mp4::Mp4Writer<BufWriter<File>>> {
        let file = File::create(&self.path).map_err(|e| Error::Io {
            path: self.path.clone(),
            source: e,
        })?;
        let brand = |s: &[u8; 4]| mp4::FourCC::from(*s);
        let config = mp4::Mp4Config {
            major_brand: brand(b"isom"),
            minor_version: 512,
            compatible_brands: vec![
                brand(b"isom"),
                brand(b"iso2"),
                brand(b"avc1"),
                brand(b"mp41"),
            ],
            timescale: 1000,
        };
        let mut mp4 = mp4::Mp4Writer::write_start(BufWriter::new(file), &config)
            .map_err(|e| failed(&self.path, e))?;
        let track = mp4::TrackConfig {
            track_type: mp4::TrackType::Video,
            timescale: TIMESCALE,
            language: "und".into(),
            media_conf: mp4::MediaConfig::AvcConfig(mp4::AvcConfig {
                width: self.width as u16,
                height: self.height as u16,
                seq_param_set: sps,
                pic_param_set: pps,
            }),
        };
        mp4.add_track(&track).map_err(|e| failed(&self.path, e))?;
        Ok(mp4)
    }

    /// Frames written so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Writes the file's index and closes it.
    pub fn finish(mut self) -> Result<u64> {
        let path = self.path.clone();
        let Some(mut mp4) = self.mp4.take() else {
            return Err(failed(&path, "no frame was written"));
        };
        mp4.write_end().map_err(|e| failed(&path, e))?;
        let mut out = mp4.into_writer();
        std::io::Write::flush(&mut out).map_err(|e| Error::Io { path, source: e })?;
        Ok(self.frames)
    }
}
