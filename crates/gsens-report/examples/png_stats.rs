//! Prints `WIDTH HEIGHT COLOURS INK` of a PNG file: its size, the number of
//! distinct colours and the fraction of pixels that are not the most common
//! colour (the background). Used by `scripts/check-report-chromium.sh` to
//! check that a screenshot shows something.

use std::collections::HashMap;

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: png_stats FILE.png");
        std::process::exit(2);
    };
    let file = std::fs::File::open(&path).unwrap_or_else(|e| {
        eprintln!("{path}: {e}");
        std::process::exit(2)
    });
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().unwrap_or_else(|e| {
        eprintln!("{path}: not a PNG: {e}");
        std::process::exit(1)
    });
    let mut buf = vec![0; reader.output_buffer_size().unwrap_or(0)];
    let info = reader.next_frame(&mut buf).unwrap_or_else(|e| {
        eprintln!("{path}: {e}");
        std::process::exit(1)
    });
    let channels = info.color_type.samples();
    let mut counts: HashMap<&[u8], usize> = HashMap::new();
    for px in buf[..info.buffer_size()].chunks_exact(channels) {
        *counts.entry(&px[..channels.min(3)]).or_default() += 1;
    }
    let total = (info.width as usize * info.height as usize).max(1);
    let background = counts.values().copied().max().unwrap_or(0);
    println!("{} {} {} {:.4}", info.width, info.height, counts.len(), 1.0 - background as f64 / total as f64);
}
