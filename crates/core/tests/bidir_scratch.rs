use gi_core::render::{BidirStrategy, Silent};
use gi_core::{render, scene::builtin, Method, Settings};
#[test]
fn scratch() {
    let scene = builtin::load("cornell").unwrap();
    let base = Settings { method: Method::Bidir, spp: 4, width: Some(48), height: Some(48), seed: 3, max_depth: 2, vpls_per_light: 16, bundles: 16, ..Default::default() };
    let path = render(&scene, &Settings { method: Method::Path, spp: 1024, ..base.clone() }, &Silent).unwrap();
    let direct = render(&scene, &Settings { method: Method::Direct, ..base.clone() }, &Silent).unwrap();
    let mut d = path.radiance.clone(); for (x, y) in d.pixels.iter_mut().zip(&direct.radiance.pixels) { *x -= *y; }
    write_pfm("/tmp/bidir/path.pfm", &d);
    for s in [BidirStrategy::Vpl, BidirStrategy::Bundle, BidirStrategy::Mis] {
        let o = render(&scene, &Settings { bidir_strategy: s, ..base.clone() }, &Silent).unwrap();
        // indirect vs reference indirect
        let mut ratios: Vec<(f32, usize)> = Vec::new();
        for i in 0..o.radiance.pixels.len() {
            let a = o.radiance.pixels[i] - direct.radiance.pixels[i];
            let b = path.radiance.pixels[i] - direct.radiance.pixels[i];
            let excess = (a.element_sum() - b.element_sum()) / path.radiance.pixels[i].element_sum().max(1e-3);
            ratios.push((excess, i));
        }
        ratios.sort_by(|x, y| y.0.partial_cmp(&x.0).unwrap());
        let mut d = o.radiance.clone(); for (x, y) in d.pixels.iter_mut().zip(&direct.radiance.pixels) { *x -= *y; }
        write_pfm(&format!("/tmp/bidir/{s:?}.pfm"), &d);
        eprintln!("{s:?}: top excess {:?}", &ratios[..6].iter().map(|(r, i)| (format!("{r:.2}"), i % 48, i / 48)).collect::<Vec<_>>());
    }
}

fn write_pfm(p: &str, img: &gi_core::image::Image) {
    let mut out = format!("PF\n{} {}\n-1\n", img.width, img.height).into_bytes();
    for y in (0..img.height).rev() { for x in 0..img.width { for c in img.get(x, y).to_array() { out.extend_from_slice(&c.to_le_bytes()); } } }
    std::fs::write(p, out).unwrap();
}
