//! PNG and JPEG images as 8-bit pictures, in pure Rust: a `CompressedImage`'s data, and the
//! frame images and still images `pvt3 import` reads from folders.

use pvt3_format::Picture;

/// A PNG image as 8-bit RGB, or grey where the file is grey: palettes expanded, 16-bit samples
/// cut to their high byte, alpha dropped.
pub fn png(bytes: &[u8]) -> Result<Picture, String> {
    let mut decoder = ::png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(::png::Transformations::EXPAND | ::png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(|e| format!("not a readable PNG ({e})"))?;
    let mut data = vec![0; reader.output_buffer_size().ok_or("a PNG too large to read")?];
    let info = reader.next_frame(&mut data).map_err(|e| format!("not a readable PNG ({e})"))?;
    data.truncate(info.buffer_size());
    let (height, width) = (info.height as usize, info.width as usize);
    let picture = |channels, data| Ok(Picture { height, width, channels, data });
    match info.color_type {
        ::png::ColorType::Grayscale => picture(1, data),
        ::png::ColorType::Rgb => picture(3, data),
        ::png::ColorType::GrayscaleAlpha => picture(1, data.chunks_exact(2).map(|p| p[0]).collect()),
        ::png::ColorType::Rgba => picture(3, data.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect()),
        other => Err(format!("a PNG of colour type {other:?}, not grey or RGB")),
    }
}

/// A JPEG image as 8-bit RGB, or grey where the file is grey.
pub fn jpeg(bytes: &[u8]) -> Result<Picture, String> {
    use zune_jpeg::zune_core::{bytestream::ZCursor, colorspace::ColorSpace, options::DecoderOptions};
    let mut decoder = zune_jpeg::JpegDecoder::new(ZCursor::new(bytes));
    decoder.decode_headers().map_err(|e| format!("not a readable JPEG ({e:?})"))?;
    let grey = decoder.input_colorspace().is_some_and(|c| c == ColorSpace::Luma);
    let out = if grey { ColorSpace::Luma } else { ColorSpace::RGB };
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), DecoderOptions::default().jpeg_set_out_colorspace(out));
    let data = decoder.decode().map_err(|e| format!("not a readable JPEG ({e:?})"))?;
    let (width, height) = decoder.dimensions().ok_or("a JPEG without dimensions")?;
    Ok(Picture { height, width, channels: out.num_components(), data })
}
