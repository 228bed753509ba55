//! The paper's figures of `host-sim reproduce` (their numbers: [`crate::report::reproduce`]):
//! Fig. 6 (b-d) time histories, Fig. 9 (m1 ≫ m2), Fig. 10 (peak against mass ratio) and Fig. 11
//! (sliding response spectra), and the velocity-dependent friction sweep, as [`Figure`]s.

use super::figure::{self, Figure, Marker, Panel, Series, Style};
use crate::report::reproduce::{Fig10, Friction, Spectra, PAPER_G};
use plotters::prelude::SeriesLabelPosition;

/// Fig. 6 (b-d): one panel per method (TFM, RFM, RDM; points (t, ü1 in gal)) over `shown` seconds,
/// each with the phase-aligned `truth`; y within ±`ylim`; `h` harmonics of TFM/RFM.
pub fn fig6_figure(
    tfm: &[(f64, f64)],
    rfm: &[(f64, f64)],
    rdm: &[(f64, f64)],
    truth: &[(f64, f64)],
    ylim: f64,
    shown: f64,
    h: u32,
) -> Figure {
    let tr = truth.to_vec();
    let mk = |title: &str, data: Vec<(f64, f64)>, ci: usize, name: &str| {
        let mut p = Panel::new(title, "time since t0 = 40 T (s), steady state", "ü1 (gal)");
        p.y_range = Some((-ylim, ylim));
        p.x_range = Some((0.0, shown));
        p.series.push(Series::new(
            "exact stick-slip truth (phase-aligned)",
            tr.clone(),
            figure::color(8),
            Style::Line(1),
        ));
        p.series
            .push(Series::new(name, data, figure::color(ci), Style::Line(2)));
        p.legend_outside = Some(340);
        p
    };
    Figure {
        title: "Fig. 6 (b-d): Table 1 specimen (29.5 kg on 1.75 kg, 7 Hz, ξ 0.05, μ 0.2), input 200 gal at T = 0.143 s".into(),
        panels: vec![
            mk("(b) TFM, trapezoid Fourier method (eq 14-18)", tfm.to_vec(), 0, &format!("TFM, {h} harmonics")),
            mk("(c) RFM, rectangular Fourier method (eq 20-22)", rfm.to_vec(), 2, &format!("RFM, {h} harmonics")),
            mk("(d) RDM, rectangular Duhamel method (eq 36), reversals every T/2", rdm.to_vec(), 1, "RDM (closed form)"),
        ],
        cols: 1,
        panel_size: (1500, 400),
    }
}

/// Fig. 9: five input periods and a zoom on one reversal, each `[friction wave, RDM]` as points
/// (t, ü1/gμ).
pub fn fig9_figure(whole: [Vec<(f64, f64)>; 2], zoom: [Vec<(f64, f64)>; 2]) -> Figure {
    let [whole_rect, whole_rdm] = whole;
    let [zoom_rect, zoom_rdm] = zoom;
    let mut a = Panel::new("ü1 over five input periods", "time t (s)", "ü1 / gμ");
    a.series.push(Series::new(
        "friction wave F/F0 (rectangular)",
        whole_rect,
        figure::color(8),
        Style::Dashed,
    ));
    a.series.push(Series::new(
        "RDM, eq (36)",
        whole_rdm,
        figure::color(0),
        Style::Line(2),
    ));
    a.y_range = Some((-1.8, 2.5));
    a.legend = SeriesLabelPosition::UpperRight;
    let mut b = Panel::new(
        "zoom on one reversal: fast, strongly damped free vibration",
        "time t (s)",
        "ü1 / gμ",
    );
    b.series.push(Series::new(
        "friction wave F/F0",
        zoom_rect,
        figure::color(8),
        Style::Dashed,
    ));
    b.series.push(Series::new(
        "RDM, eq (36)",
        zoom_rdm,
        figure::color(0),
        Style::Line(2),
    ));
    b.y_range = Some((-1.8, 2.5));
    b.legend = SeriesLabelPosition::UpperRight;
    Figure {
        title: "Fig. 9: response when m1 >> m2: (m1+m2)/m2 = 100, μ 0.2, ξ 0.05, p = 2π·5 rad/s, T = 0.2 s".into(),
        panels: vec![a, b],
        cols: 2,
        panel_size: (950, 560),
    }
}

/// Fig. 10: one panel per damping ratio, one curve per input period.
pub fn fig10_figure(r: &Fig10) -> Figure {
    let (t0, xis, periods, ms, peaks) = (
        r.natural_period_s,
        &r.xis,
        &r.periods_s,
        &r.mass_ratios,
        &r.peaks_gmu,
    );
    let mut panels = Vec::new();
    for (a, &xi) in xis.iter().enumerate() {
        let mut p = Panel::new(
            format!("({}) ξ = {xi}", ["a", "b", "c", "d"][a]),
            "mass ratio M = (m1+m2)/m2 (log)",
            "steady-state peak |ü1| / gμ",
        );
        p.log_x = true;
        for (b, &period) in periods.iter().enumerate() {
            let pts: Vec<(f64, f64)> = ms
                .iter()
                .copied()
                .zip(peaks[a][b].iter().copied())
                .collect();
            p.series.push(Series::new(
                format!("T = {period:.2} s (T/T0 = {:.2})", period / t0),
                pts,
                figure::color(b),
                Style::Line(2),
            ));
        }
        p.legend_outside = Some(260);
        panels.push(p);
    }
    Figure {
        title: format!(
            "Fig. 10: steady-state RDM peak against mass ratio M for ten input periods (T0 = {t0} s, μ 0.2)"
        ),
        panels,
        cols: 2,
        panel_size: (1100, 620),
    }
}

/// Fig. 11: (a) the harmonic spectrum, (b) the El Centro spectrum of the structure
/// (m1, m2, ξ, μ), the latter over `quake_duration` seconds.
pub fn spectra_figure(
    r: &Spectra,
    (m1, m2, xi, mu): (f64, f64, f64, f64),
    quake_duration: f64,
) -> Figure {
    let (a0, period, gmu, mu_s) = (
        r.harmonic_a0_m_s2,
        r.harmonic_period_s,
        r.gmu_m_s2,
        r.quake_mu_static,
    );
    let (harmonic, quake_pts) = (&r.harmonic, &r.quake);
    let mut a = Panel::new(
        format!("(a) harmonic input {a0} m/s² at T = {period} s (steady state)"),
        "natural period T0 (s, log)",
        "peak |ü1| (m/s²)",
    );
    a.log_x = true;
    a.log_y = true;
    a.series.push(Series::new(
        "fixed base (no sliding)",
        harmonic
            .iter()
            .map(|p| (p.natural_period_s, p.fixed_base))
            .collect(),
        figure::color(8),
        Style::Dashed,
    ));
    a.series.push(Series::new(
        "exact stick-slip truth",
        harmonic
            .iter()
            .map(|p| (p.natural_period_s, p.truth))
            .collect(),
        figure::color(1),
        Style::LineMarkers(Marker::Circle, 4),
    ));
    a.series.push(Series::new(
        "TFM (fixed base when βA0 ≤ gμ)",
        harmonic
            .iter()
            .map(|p| (p.natural_period_s, p.tfm))
            .collect(),
        figure::color(0),
        Style::Line(2),
    ));
    a.series.push(Series::new(
        "RFM = RDM steady state (sliding only)",
        harmonic
            .iter()
            .filter_map(|p| p.rfm.map(|v| (p.natural_period_s, v)))
            .collect(),
        figure::color(2),
        Style::Markers(Marker::Triangle, 5),
    ));
    a.series.push(Series::new(
        "gμ",
        vec![(0.05, gmu), (2.0, gmu)],
        figure::color(6),
        Style::Dashed,
    ));
    a.x_range = Some((0.045, 2.2));
    a.legend_outside = Some(360);
    let mut b = Panel::new(
        format!("(b) El Centro 1940 NS (μ {mu}, μs {mu_s}), peak over {quake_duration} s"),
        "natural period T0 (s, log)",
        "peak |ü1| (m/s²)",
    );
    b.log_x = true;
    b.log_y = true;
    b.series.push(Series::new(
        "fixed base (no sliding)",
        quake_pts
            .iter()
            .map(|p| (p.natural_period_s, p.fixed_base))
            .collect(),
        figure::color(8),
        Style::Dashed,
    ));
    b.series.push(Series::new(
        "exact stick-slip truth",
        quake_pts
            .iter()
            .map(|p| (p.natural_period_s, p.truth))
            .collect(),
        figure::color(1),
        Style::LineMarkers(Marker::Circle, 4),
    ));
    b.series.push(Series::new(
        "RDM, the truth's friction train",
        quake_pts
            .iter()
            .filter_map(|p| p.rdm_truth_train.map(|v| (p.natural_period_s, v)))
            .collect(),
        figure::color(2),
        Style::Markers(Marker::Triangle, 5),
    ));
    b.series.push(Series::new(
        "gμ",
        vec![(0.05, gmu), (2.0, gmu)],
        figure::color(6),
        Style::Dashed,
    ));
    b.x_range = Some((0.045, 2.2));
    b.legend_outside = Some(360);
    Figure {
        title: format!(
            "Fig. 11: sliding response spectra, m1/m2 = {m1}/{m2}, ξ {xi}, μ {mu} (g = {PAPER_G})"
        ),
        panels: vec![a, b],
        cols: 1,
        panel_size: (1500, 600),
    }
}

/// The velocity-dependent friction sweep: steady-state peak over the Coulomb peak against
/// μ_slow/μ_fast, one panel per input period, one line per rate a, and the paper's Coulomb
/// prediction (ratio 1).
pub fn friction_figure(r: &Friction) -> Figure {
    let lo = r.mu_ratios.iter().copied().fold(1.0, f64::min);
    let ymin = r
        .cases
        .iter()
        .flat_map(|c| c.points.iter().flatten())
        .map(|p| p.peak_over_coulomb)
        .filter(|v| v.is_finite())
        .fold(1.0, f64::min);
    let ymax = r
        .cases
        .iter()
        .flat_map(|c| c.points.iter().flatten())
        .map(|p| p.peak_over_coulomb)
        .filter(|v| v.is_finite())
        .fold(1.0, f64::max);
    let x_range = (lo - 0.03, 1.03);
    let y_range = ((ymin - 0.05).min(0.9), (ymax + 0.05).max(1.05));
    let panels = r
        .cases
        .iter()
        .enumerate()
        .map(|(i, case)| {
            let mut p = Panel::new(
                format!(
                    "({}) input {} m/s² at T = {} s; Coulomb peak {:.3} gμ_fast (g = {PAPER_G})",
                    ["a", "b", "c", "d"][i % 4],
                    r.a0_m_s2,
                    case.period_s,
                    case.coulomb_peak_gmu
                ),
                "μ_slow / μ_fast (μs = μ_slow)",
                "steady-state peak |ü1| / Coulomb peak",
            );
            p.x_range = Some(x_range);
            p.y_range = Some(y_range);
            p.series.push(Series::new(
                format!("paper's Coulomb prediction (μ = μ_fast = {})", r.mu_fast),
                vec![(x_range.0, 1.0), (x_range.1, 1.0)],
                figure::color(6),
                Style::Dashed,
            ));
            for (a, (&rate, row)) in r.rates_s_m.iter().zip(&case.points).enumerate() {
                p.series.push(Series::new(
                    format!("a = {rate} s/m"),
                    row.iter()
                        .map(|pt| (pt.mu_ratio, pt.peak_over_coulomb))
                        .collect(),
                    figure::color(a),
                    Style::LineMarkers(Marker::Circle, 5),
                ));
            }
            p.legend_outside = Some(440);
            p
        })
        .collect();
    Figure {
        title: "Velocity-dependent friction μ(v) = μ_fast − (μ_fast − μ_slow)·e^(−a|v|), Table 1 specimen"
            .into(),
        panels,
        cols: 1,
        panel_size: (1500, 520),
    }
}
