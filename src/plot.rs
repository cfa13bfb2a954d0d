//! Log-log plots (SVG or PNG, through plotters) shared by `chambre bench scale` and
//! `chambre converge`.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

/// The plots' typeface, shipped so that a PNG has the same text on every machine
/// (`assets/fonts/DejaVuSans-LICENSE.txt`).
const FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// A figure plotters can draw on any backend.
pub trait Figure {
    /// Width and height, in pixels of the PNG (and units of the SVG).
    fn size(&self) -> (u32, u32);
    /// Draws the whole figure on `root` (its background included); the error as a message.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
}

/// `figure` as the file `path` names: PNG bytes for a `.png`, SVG text otherwise.
pub fn figure_bytes(figure: &impl Figure, path: &Path) -> Result<Vec<u8>, String> {
    static FONT_REGISTERED: std::sync::Once = std::sync::Once::new();
    FONT_REGISTERED.call_once(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .unwrap_or_else(|_| panic!("the shipped DejaVu Sans is a valid font"));
    });
    let (width, height) = figure.size();
    let png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !png {
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
            figure.draw(&root)?;
            root.present().map_err(|e| e.to_string())?;
        }
        return Ok(svg.into_bytes());
    }
    let mut rgb = vec![0u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        figure.draw(&root)?;
        root.present().map_err(|e| e.to_string())?;
    }
    let mut bytes = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut bytes),
        &rgb,
        width,
        height,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// A curve: its legend, its points, its colour.
pub type Series<'a> = (&'a str, &'a [(f64, f64)], RGBColor);

/// One log-log panel: each series a labelled line through its points, on axes named `x_desc`
/// and `y_desc`.
pub fn log_log_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
    x_range: std::ops::Range<f64>,
) -> std::result::Result<(), String> {
    let values = series.iter().flat_map(|(_, s, _)| s.iter().map(|p| p.1));
    let (lo, hi) = values.fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(x_range.log_scale(), (lo * 0.7..hi * 1.4).log_scale())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(8)
        .y_labels(8)
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| tick_label(*v))
        .draw()
        .map_err(|e| e.to_string())?;
    for &(name, points, color) in series {
        if points.is_empty() {
            continue;
        }
        chart
            .draw_series(LineSeries::new(points.iter().copied(), color))
            .map_err(|e| e.to_string())?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 3, color.filled())))
            .map_err(|e| e.to_string())?;
    }
    chart
        .configure_series_labels()
        // Error curves fall to the right: the top right corner is empty.
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())
}

/// A tick value with three significant digits at most: `0.7`, `12.5`, `3.0e-5`.
fn tick_label(v: f64) -> String {
    let magnitude = v.abs();
    if v == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&magnitude) {
        format!("{v:.1e}")
    } else {
        let decimals = (2 - magnitude.log10().floor() as i32).max(0) as usize;
        let text = format!("{v:.decimals$}");
        match text.contains('.') {
            true => text.trim_end_matches('0').trim_end_matches('.').into(),
            false => text,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::tick_label;

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(0.7000000000000001), "0.7");
        assert_eq!(tick_label(10.0), "10");
        assert_eq!(tick_label(12.5), "12.5");
        assert_eq!(tick_label(2000.0), "2000");
        assert_eq!(tick_label(0.00123), "0.00123");
        assert_eq!(tick_label(3e-5), "3.0e-5");
        assert_eq!(tick_label(0.0), "0");
    }
}
