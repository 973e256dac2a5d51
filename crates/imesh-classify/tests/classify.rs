//! Classifiers on real fixture images, and bad input.

use std::path::{Path, PathBuf};

use image::{DynamicImage, GenericImageView, GrayImage, ImageBuffer, Luma, LumaA, Rgb, RgbImage};
use imesh_classify::{
    classify, kmeans, label_map, load_image, looks_like_label_map, majority_filter,
    multi_otsu_levels, remove_small_regions, Classifier, ClassifyError, ClassifyOptions, LabelGrid,
    Region, TextureClassifier, TextureSamples, DEFAULT_MAX_PIXELS,
};

fn fixture_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/images")
        .join(name)
}

fn fixture(name: &str) -> DynamicImage {
    load_image(&fixture_path(name), DEFAULT_MAX_PIXELS).unwrap()
}

/// A scratch directory, removed with everything in it when dropped.
fn temp_dir() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("imesh-classify-")
        .tempdir()
        .unwrap()
}

#[test]
fn otsu_matches_imageproc_on_grey_fixtures() {
    for name in [
        "skimage-camera.png",
        "skimage-coins.png",
        "matplotlib-s1045_mri.png",
    ] {
        let grey = fixture(name).to_luma8();
        let reference = imageproc::contrast::otsu_level(&grey);
        // Our multi-level dynamic programme with two classes must find the same level.
        assert_eq!(multi_otsu_levels(&grey, 2), vec![reference], "{name}");
        let grid = classify(
            &fixture(name),
            &Classifier::Otsu { classes: 2 },
            &ClassifyOptions::default(),
        )
        .unwrap();
        for (i, &v) in grey.as_raw().iter().enumerate() {
            assert_eq!(grid.labels()[i], u32::from(v > reference));
        }
    }
}

#[test]
fn multi_otsu_splits_the_mri_into_ordered_classes() {
    let img = fixture("matplotlib-s1045_mri.png");
    let grey = img.to_luma8();
    let levels = multi_otsu_levels(&grey, 4);
    assert_eq!(levels.len(), 3);
    assert!(levels.windows(2).all(|w| w[0] < w[1]), "{levels:?}");
    let grid = classify(
        &img,
        &"otsu:4".parse().unwrap(),
        &ClassifyOptions::default(),
    )
    .unwrap();
    assert_eq!(grid.num_labels(), 4);
    // Brighter pixels never get a lower class.
    let mut class_max = [0u8; 4];
    for (i, &v) in grey.as_raw().iter().enumerate() {
        let c = grid.labels()[i] as usize;
        class_max[c] = class_max[c].max(v);
    }
    assert!(class_max.windows(2).all(|w| w[0] < w[1]));
}

#[test]
fn explicit_thresholds() {
    let img = fixture("skimage-camera.png");
    let grid = classify(
        &img,
        &"threshold:80,170".parse().unwrap(),
        &ClassifyOptions::default(),
    )
    .unwrap();
    let grey = img.to_luma8();
    for (i, &v) in grey.as_raw().iter().enumerate().step_by(97) {
        let expected = if v <= 80 {
            0
        } else if v <= 170 {
            1
        } else {
            2
        };
        assert_eq!(grid.labels()[i], expected);
    }
    assert_eq!(grid.regions()[1].name, "luminance 81–170");
}

#[test]
fn kmeans_is_deterministic_and_blind_to_pixel_order() {
    let img = fixture("skimage-coffee.png");
    let a = kmeans(&img, 4);
    let b = kmeans(&img, 4);
    assert_eq!(a, b);
    assert_eq!(a.num_labels(), 4);
    // Clusters are ordered by lightness: the mean colours' luminance increases.
    let lum =
        |c: [u8; 3]| 0.2126 * f64::from(c[0]) + 0.7152 * f64::from(c[1]) + 0.0722 * f64::from(c[2]);
    let l: Vec<f64> = a.regions().iter().map(|r| lum(r.colour)).collect();
    assert!(l.windows(2).all(|w| w[0] <= w[1] + 20.0), "{l:?}");
    // Permute the pixels (a fixed pseudo-random bijection): every pixel keeps its label.
    let (w, h) = img.dimensions();
    let n = (w * h) as u64;
    let perm = |i: u64| (i * 7_919 + 13) % n; // 7919 is prime and does not divide 240000
    let rgb = img.to_rgb8();
    let mut shuffled = RgbImage::new(w, h);
    for i in 0..n {
        let j = perm(i);
        shuffled.put_pixel(
            (j % u64::from(w)) as u32,
            (j / u64::from(w)) as u32,
            *rgb.get_pixel((i % u64::from(w)) as u32, (i / u64::from(w)) as u32),
        );
    }
    let c = kmeans(&DynamicImage::ImageRgb8(shuffled), 4);
    for i in 0..n {
        assert_eq!(c.labels()[perm(i) as usize], a.labels()[i as usize]);
    }
}

#[test]
fn label_maps_round_trip_through_a_colour_png() {
    for (name, expected) in [
        ("pyvista-channels_z050_labels.png", 5),
        ("stardist-mask2d_labels.png", 126),
    ] {
        let img = fixture(name);
        assert!(looks_like_label_map(&img, 256), "{name}");
        let grid = label_map(&img, 256).unwrap();
        assert_eq!(grid.num_labels(), expected, "{name}");
        assert_eq!(grid.regions()[0].name, "value 0");
        // Auto picks the label map.
        assert_eq!(
            classify(&img, &Classifier::Auto, &ClassifyOptions::default()).unwrap(),
            grid
        );
        // Labels are the grey values' order: pixel value v has label rank(v).
        let grey = img.to_luma8();
        let mut values: Vec<u8> = grey.as_raw().clone();
        values.sort_unstable();
        values.dedup();
        for (i, &v) in grey.as_raw().iter().enumerate().step_by(13) {
            assert_eq!(grid.labels()[i] as usize, values.binary_search(&v).unwrap());
        }
        // Written as colours and read back, the partition is the same (colours are distinct).
        if expected <= 12 {
            let dir = temp_dir();
            let path = dir.path().join(format!("{name}.png"));
            grid.save_png(&path).unwrap();
            let back = label_map(&load_image(&path, DEFAULT_MAX_PIXELS).unwrap(), 256).unwrap();
            assert_eq!(back.num_labels(), grid.num_labels());
            let mut map = vec![u32::MAX; grid.num_labels()];
            for (a, b) in grid.labels().iter().zip(back.labels()) {
                let m = &mut map[*a as usize];
                assert!(*m == u32::MAX || *m == *b, "a label split in two");
                *m = *b;
            }
        }
    }
}

#[test]
fn auto_thresholds_a_photograph() {
    let img = fixture("skimage-camera.png");
    assert!(!looks_like_label_map(&img, 256));
    let grid = classify(&img, &Classifier::Auto, &ClassifyOptions::default()).unwrap();
    assert_eq!(grid.num_labels(), 2);
}

#[test]
fn deep_and_alpha_images_load_and_label() {
    let scratch = temp_dir();
    let dir = scratch.path();
    let deep: ImageBuffer<Luma<u16>, Vec<u16>> =
        ImageBuffer::from_fn(20, 10, |x, _| Luma([if x < 10 { 1000 } else { 60000 }]));
    let p16 = dir.join("deep.png");
    deep.save(&p16).unwrap();
    let grid = label_map(&load_image(&p16, DEFAULT_MAX_PIXELS).unwrap(), 256).unwrap();
    assert_eq!(grid.num_labels(), 2);
    assert_eq!(grid.regions()[1].name, "value 60000");
    let alpha: ImageBuffer<LumaA<u8>, Vec<u8>> =
        ImageBuffer::from_fn(8, 8, |x, y| LumaA([if x + y < 8 { 0 } else { 255 }, 255]));
    let pa = dir.join("alpha.png");
    alpha.save(&pa).unwrap();
    assert_eq!(
        label_map(&load_image(&pa, DEFAULT_MAX_PIXELS).unwrap(), 256)
            .unwrap()
            .num_labels(),
        2
    );
}

/// A grey TIFF of `width` × `height` samples of colour type `C`, written by the `tiff` crate.
fn grey_tiff<C: tiff::encoder::colortype::ColorType>(
    path: &Path,
    width: u32,
    height: u32,
    samples: &[C::Inner],
) where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let file = std::fs::File::create(path).unwrap();
    tiff::encoder::TiffEncoder::new(file)
        .unwrap()
        .write_image::<C>(width, height, samples)
        .unwrap();
}

#[test]
fn grey_tiffs_of_every_sample_type_load() {
    use tiff::encoder::colortype::{Gray32, Gray32Float, Gray64Float, GrayI16, GrayI32};
    let scratch = temp_dir();
    let dir = scratch.path();
    // The `image` crate decodes none of these five.
    // A 32-bit label map: its ids are its region names.
    let ids: Vec<u32> = (0..200).map(|i| [0, 7, 4000][i % 20 / 7]).collect();
    let p = dir.join("labels-u32.tif");
    grey_tiff::<Gray32>(&p, 20, 10, &ids);
    let grid = label_map(&load_image(&p, DEFAULT_MAX_PIXELS).unwrap(), 256).unwrap();
    let names: Vec<&str> = grid.regions().iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["value 0", "value 7", "value 4000"]);
    assert_eq!((grid.label(0, 0), grid.label(19, 9)), (0, 2));
    // Ids over 16 bits stay apart, in their order.
    let wide: Vec<i32> = (0..200)
        .map(|i| [-5, 1, 2, 900_000_000][i % 20 / 5])
        .collect();
    let p = dir.join("labels-i32.tif");
    grey_tiff::<GrayI32>(&p, 20, 10, &wide);
    let grid = label_map(&load_image(&p, DEFAULT_MAX_PIXELS).unwrap(), 256).unwrap();
    assert_eq!(grid.num_labels(), 4);
    assert!((0..4).all(|k| grid.label(5 * k, 3) == k));
    // A CT slice in Hounsfield units (air −1 000, a disc of bone 1 500): Otsu finds the disc.
    let ct: Vec<i16> = (0..1600)
        .map(|i| {
            let (x, y) = (i % 40 - 20, i / 40 - 20);
            if x * x + y * y < 100 {
                1500 + (i % 7) as i16
            } else {
                -1000 + (i % 5) as i16
            }
        })
        .collect();
    let p = dir.join("ct-i16.tif");
    grey_tiff::<GrayI16>(&p, 40, 40, &ct);
    let img = load_image(&p, DEFAULT_MAX_PIXELS).unwrap();
    assert!(matches!(img, DynamicImage::ImageLuma16(_)));
    let grid = classify(&img, &"otsu".parse().unwrap(), &ClassifyOptions::default()).unwrap();
    assert_eq!((grid.label(20, 20), grid.label(0, 0)), (1, 0));
    // Floating point, with a not-a-number hole: the hole takes the lowest level.
    let mut field: Vec<f32> = (0..1600).map(|i| (i % 40) as f32 * 0.01).collect();
    field[0] = f32::NAN;
    let p = dir.join("field-f32.tif");
    grey_tiff::<Gray32Float>(&p, 40, 40, &field);
    let DynamicImage::ImageLuma16(grey) = load_image(&p, DEFAULT_MAX_PIXELS).unwrap() else {
        panic!("a float TIFF loads as 16-bit grey");
    };
    assert_eq!(
        (grey[(0, 0)][0], grey[(0, 1)][0], grey[(39, 0)][0]),
        (0, 0, 65535)
    );
    assert!((1..40).all(|x| grey[(x - 1, 1)][0] < grey[(x, 1)][0]));
    let p = dir.join("field-f64.tif");
    let field: Vec<f64> = field.iter().map(|&v| f64::from(v)).collect();
    grey_tiff::<Gray64Float>(&p, 40, 40, &field);
    assert_eq!(
        load_image(&p, DEFAULT_MAX_PIXELS).unwrap().to_luma16(),
        grey
    );
    // The pixel limit holds before decoding.
    let e = load_image(&p, 1000).unwrap_err();
    assert!(
        matches!(e, ClassifyError::TooLarge { pixels: 1600, .. }),
        "{e}"
    );
    // A TIFF neither decoder reads (cut short) is still a clear error.
    let bytes = std::fs::read(&p).unwrap();
    let cut = dir.join("cut.tif");
    std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
    let e = load_image(&cut, DEFAULT_MAX_PIXELS).unwrap_err();
    assert!(matches!(e, ClassifyError::Decode { .. }), "{e}");
}

/// The CRC of a PNG chunk's type and data.
fn png_crc(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

#[test]
fn a_photograph_is_meshed_as_its_orientation_tag_shows_it() {
    let scratch = temp_dir();
    let dir = scratch.path();
    // 3 × 2 pixels, the stored top-left one white; EXIF orientation 6: shown turned 90°
    // clockwise, 2 × 3, the white pixel at the top right.
    let stored = GrayImage::from_fn(3, 2, |x, y| Luma([if (x, y) == (0, 0) { 255 } else { 0 }]));
    let mut png = Vec::new();
    stored
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    // A big-endian TIFF header and one IFD entry: Orientation (0x0112), SHORT, 1 value, 6.
    let exif: [u8; 26] = [
        b'M', b'M', 0, 42, 0, 0, 0, 8, 0, 1, 0x01, 0x12, 0, 3, 0, 0, 0, 1, 0, 6, 0, 0, 0, 0, 0, 0,
    ];
    let mut chunk = (exif.len() as u32).to_be_bytes().to_vec();
    let typed: Vec<u8> = b"eXIf".iter().chain(&exif).copied().collect();
    chunk.extend(&typed);
    chunk.extend(png_crc(&typed).to_be_bytes());
    // After the signature and IHDR (8 + 25 bytes).
    png.splice(33..33, chunk);
    let p = dir.join("turned.png");
    std::fs::write(&p, &png).unwrap();
    let shown = load_image(&p, DEFAULT_MAX_PIXELS).unwrap().to_luma8();
    assert_eq!(shown.dimensions(), (2, 3));
    assert_eq!(shown.as_raw(), &[0, 255, 0, 0, 0, 0]);
    // A grey TIFF the `tiff` crate reads, with the same tag.
    let p = dir.join("turned-f32.tif");
    {
        let file = std::fs::File::create(&p).unwrap();
        let mut tiff = tiff::encoder::TiffEncoder::new(file).unwrap();
        let mut image = tiff
            .new_image::<tiff::encoder::colortype::Gray32Float>(3, 2)
            .unwrap();
        image
            .encoder()
            .write_tag(tiff::tags::Tag::Orientation, 6u16)
            .unwrap();
        image.write_data(&[0.5, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    }
    let shown = load_image(&p, DEFAULT_MAX_PIXELS).unwrap().to_luma16();
    assert_eq!(shown.dimensions(), (2, 3));
    assert_eq!(shown.as_raw(), &[0, 65535, 0, 0, 0, 0]);
}

#[test]
fn a_deep_image_using_few_of_its_levels_is_classified_on_its_own_range() {
    // A 12-bit camera's micrograph in a 16-bit file: background 1 000, a disc 120 brighter,
    // noise of ±40 (on 8 bits, /257, nearly every pixel falls on level 4).
    let noise = |x: u32, y: u32| ((x * 7919 + y * 104_729) % 81) as u16;
    let inside = |x: u32, y: u32| (x as i32 - 40).pow(2) + (y as i32 - 30).pow(2) < 400;
    let img: ImageBuffer<Luma<u16>, Vec<u16>> = ImageBuffer::from_fn(80, 60, |x, y| {
        Luma([960 + noise(x, y) + if inside(x, y) { 120 } else { 0 }])
    });
    let img = DynamicImage::ImageLuma16(img);
    for classifier in ["auto", "otsu", "kmeans:2"] {
        let grid = classify(
            &img,
            &classifier.parse().unwrap(),
            &ClassifyOptions::default(),
        )
        .unwrap();
        let wrong = (0..60)
            .flat_map(|y| (0..80).map(move |x| (x, y)))
            .filter(|&(x, y)| (grid.label(x, y) == 1) != inside(x, y))
            .count();
        assert!(
            wrong < 4800 / 20,
            "{classifier}: {wrong} of 4 800 pixels on the wrong side"
        );
    }
}

#[test]
fn a_flat_picture_stored_as_jpeg_is_read_by_its_dominant_colours() {
    let scratch = temp_dir();
    let dir = scratch.path();
    // Three flat greys: a dark disc and a mid-grey bar on white, saved as a JPEG of quality
    // 90 (its flat blocks come back exact: a label map to `auto`).
    let truth = |x: u32, y: u32| {
        if (x as i32 - 160).pow(2) + (y as i32 - 160).pow(2) < 10_000 {
            0
        } else if (300..380).contains(&x) {
            1
        } else {
            2
        }
    };
    let greys = [30, 120, 255];
    let img = GrayImage::from_fn(400, 320, |x, y| Luma([greys[truth(x, y)]]));
    let path = dir.join("flat.jpg");
    let file = std::fs::File::create(&path).unwrap();
    image::codecs::jpeg::JpegEncoder::new_with_quality(file, 90)
        .encode_image(&img)
        .unwrap();
    let loaded = load_image(&path, DEFAULT_MAX_PIXELS).unwrap();
    assert!(imesh_classify::is_lossy_file(&path));
    // Every grey a label: the codec's shades along the edges make dozens of them.
    let every = classify(&loaded, &Classifier::Auto, &ClassifyOptions::default()).unwrap();
    assert!(every.num_labels() > 10, "{} labels", every.num_labels());
    let options = ClassifyOptions {
        lossy: true,
        ..ClassifyOptions::default()
    };
    let grid = classify(&loaded, &Classifier::Auto, &options).unwrap();
    assert_eq!(grid.num_labels(), 3);
    let wrong = (0..320)
        .flat_map(|y| (0..400).map(move |x| (x, y)))
        .filter(|&(x, y)| grid.label(x, y) as usize != truth(x, y))
        .count();
    assert!(
        wrong < 128_000 / 100,
        "{wrong} of 128 000 pixels mislabelled"
    );
    // A lossless file of the same picture is not lossy.
    let png = dir.join("flat.png");
    img.save(&png).unwrap();
    assert!(!imesh_classify::is_lossy_file(&png));
}

#[test]
fn lossy_webp_and_avif_are_told_from_lossless_ones() {
    let scratch = temp_dir();
    let dir = scratch.path();
    let lossy = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        imesh_classify::is_lossy_file(&p)
    };
    assert!(lossy("a.webp", b"RIFF\x20\0\0\0WEBPVP8 \x0a\0\0\0"));
    assert!(!lossy("b.webp", b"RIFF\x20\0\0\0WEBPVP8L\x0a\0\0\0"));
    // The extended format: a VP8X chunk of 10 bytes, then an odd-sized ALPH chunk (padded),
    // then the bitstream.
    let mut extended = b"RIFF\0\0\0\0WEBPVP8X\x0a\0\0\0".to_vec();
    extended.extend([0; 10]);
    extended.extend(b"ALPH\x03\0\0\0\x01\x02\x03\0VP8 \x04\0\0\0");
    assert!(lossy("c.webp", &extended));
    assert!(lossy("d.avif", b"\0\0\0\x20ftypavif\0\0\0\0"));
    assert!(!lossy("e.bin", b"not an image at all"));
    assert!(!lossy("f.jpg", b"\xff\xd8"));
    assert!(!imesh_classify::is_lossy_file(&dir.join("missing.jpg")));
}

#[test]
fn noise_has_too_many_values_for_a_label_map() {
    let img = DynamicImage::ImageRgb8(RgbImage::from_fn(64, 64, |x, y| {
        Rgb([x as u8 * 4, y as u8 * 4, (x * y) as u8])
    }));
    let err = label_map(&img, 256).unwrap_err();
    assert!(matches!(err, ClassifyError::TooManyLabels { limit: 256 }));
    assert!(
        err.to_string().contains("kmeans"),
        "the message gives advice: {err}"
    );
    assert_eq!(label_map(&img, 5000).unwrap().num_labels(), 4096);
}

#[test]
fn bad_files_are_clear_errors() {
    let scratch = temp_dir();
    let dir = scratch.path();
    let missing = load_image(&dir.join("nope.png"), DEFAULT_MAX_PIXELS).unwrap_err();
    assert!(matches!(missing, ClassifyError::Io { .. }), "{missing}");
    // A truncated PNG: the first half of a real one.
    let bytes = std::fs::read(fixture_path("pyvista-channels_z050_labels.png")).unwrap();
    let cut = dir.join("truncated.png");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = load_image(&cut, DEFAULT_MAX_PIXELS).unwrap_err();
    assert!(matches!(e, ClassifyError::Decode { .. }), "{e}");
    // Not an image at all.
    let text = dir.join("text.png");
    std::fs::write(&text, "hello").unwrap();
    assert!(matches!(
        load_image(&text, DEFAULT_MAX_PIXELS).unwrap_err(),
        ClassifyError::Decode { .. }
    ));
    // An empty 0 × 0 image (a PNM header).
    let empty = dir.join("empty.pgm");
    std::fs::write(&empty, "P5\n0 0\n255\n").unwrap();
    let e = load_image(&empty, DEFAULT_MAX_PIXELS).unwrap_err();
    assert!(
        matches!(
            e,
            ClassifyError::EmptyImage { .. } | ClassifyError::Decode { .. }
        ),
        "{e}"
    );
    // Over the pixel limit: refused before decoding.
    let e = load_image(&fixture_path("skimage-camera.png"), 1000).unwrap_err();
    assert!(
        matches!(
            e,
            ClassifyError::TooLarge {
                width: 512,
                height: 512,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn bad_specs_are_clear_errors() {
    for spec in [
        "",
        "otsu:1",
        "otsu:x",
        "threshold:",
        "threshold:200,100",
        "threshold:300",
        "kmeans",
        "kmeans:100",
        "texture:",
        "sobel",
    ] {
        let e = spec.parse::<Classifier>().unwrap_err();
        assert!(matches!(e, ClassifyError::BadSpec { .. }), "{spec}: {e}");
    }
}

#[test]
fn bad_sample_files_are_clear_errors() {
    let p: &Path = "samples.toml".as_ref();
    let single = "[[label]]\nname = \"a\"\nrectangles = [[0, 0, 4, 4]]\n";
    let e = TextureSamples::parse(single, p).unwrap_err();
    assert!(e.to_string().contains("at least two labels"), "{e}");
    let malformed = "[[label]]\nname = \"a\"\nrectangles = [[0, 0, 4]]\n[[label]]\nname = \"b\"\nrectangles = [[0, 0, 4, 4]]\n";
    let e = TextureSamples::parse(malformed, p).unwrap_err();
    assert!(matches!(e, ClassifyError::Samples { .. }), "{e}");
    assert!(
        e.to_string().contains("line 3"),
        "the error names the line: {e}"
    );
    let garbage = "window = = 3";
    assert!(TextureSamples::parse(garbage, p).is_err());
    let unknown = "windw = 3\n";
    assert!(TextureSamples::parse(unknown, p)
        .unwrap_err()
        .to_string()
        .contains("windw"));
    let even = "window = 4\n[[label]]\nname = \"a\"\nrectangles = [[0, 0, 4, 4]]\n[[label]]\nname = \"b\"\nrectangles = [[4, 0, 4, 4]]\n";
    assert!(TextureSamples::parse(even, p)
        .unwrap_err()
        .to_string()
        .contains("odd"));
    // A rectangle outside the image.
    let ok = "[[label]]\nname = \"a\"\nrectangles = [[0, 0, 4, 4]]\n[[label]]\nname = \"b\"\nrectangles = [[10, 0, 8, 4]]\n";
    let samples = TextureSamples::parse(ok, p).unwrap();
    let img = DynamicImage::ImageLuma8(image::GrayImage::new(16, 16));
    let e = TextureClassifier::train(&img, &samples).err().unwrap();
    assert!(
        matches!(
            e,
            ClassifyError::RectangleOutside {
                rect: [10, 0, 8, 4],
                ..
            }
        ),
        "{e}"
    );
    // A missing sample file through the spec.
    let e = classify(
        &img,
        &"texture:/nonexistent/s.toml".parse().unwrap(),
        &ClassifyOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, ClassifyError::Io { .. }));
}

fn grid_of(w: u32, rows: &[&str]) -> LabelGrid {
    let labels: Vec<u32> = rows
        .iter()
        .flat_map(|r| r.bytes().map(|b| u32::from(b - b'0')))
        .collect();
    let n = labels.iter().max().map_or(0, |&m| m + 1);
    let regions = (0..n)
        .map(|i| Region {
            name: format!("r{i}"),
            colour: [0, 0, 0],
        })
        .collect();
    LabelGrid::new(w, rows.len() as u32, labels, regions).unwrap()
}

#[test]
fn small_regions_merge_into_their_longest_border_neighbour() {
    let g = grid_of(6, &["000111", "020111", "000111", "000131", "000111"]);
    let clean = remove_small_regions(&g, 2);
    // The single 2 sits inside 0, the single 3 inside 1.
    let expected = grid_of(6, &["000111", "000111", "000111", "000111", "000111"]);
    assert_eq!(clean.labels(), expected.labels());
    assert_eq!(clean.num_labels(), 2);
    // A region touching two others goes to the one it shares more border with.
    let g = grid_of(4, &["0011", "0211", "0211", "0011"]);
    let clean = remove_small_regions(&g, 3);
    assert_eq!(clean.label(1, 1), clean.label(0, 0));
    // Nothing smaller than the limit: unchanged. The whole image small: kept.
    assert_eq!(remove_small_regions(&g, 1), g);
    let one = grid_of(2, &["00"]);
    assert_eq!(remove_small_regions(&one, 100), one);
}

#[test]
fn majority_filter_removes_speckle_and_keeps_ties() {
    let g = grid_of(5, &["00000", "00100", "00000", "11111", "11111"]);
    let f = majority_filter(&g, 1, 1);
    assert_eq!(f.label(2, 1), 0);
    // On the straight 0/1 border, each side keeps its label.
    assert_eq!(f.label(2, 2), 0);
    assert_eq!(f.label(2, 3), 1);
}
