//! A rectangle of an image, in pixels, half-open: what a render split by
//! regions renders and what `vkpt merge` assembles (as pbrt's crop window
//! and OpenEXR's data window inside its display window).

use std::fmt;

/// Pixels `x0 <= x < x1`, `y0 <= y < y1` of an image, y = 0 at the top.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Region {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Region {
    /// The whole of a `width` x `height` image.
    pub fn full(width: u32, height: u32) -> Region {
        Region {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    pub fn width(&self) -> u32 {
        self.x1.saturating_sub(self.x0)
    }

    pub fn height(&self) -> u32 {
        self.y1.saturating_sub(self.y0)
    }

    pub fn pixel_count(&self) -> u64 {
        self.width() as u64 * self.height() as u64
    }

    pub fn is_full(&self, width: u32, height: u32) -> bool {
        *self == Region::full(width, height)
    }

    /// Whether the two rectangles share a pixel.
    pub fn overlaps(&self, other: &Region) -> bool {
        self.x0 < other.x1 && other.x0 < self.x1 && self.y0 < other.y1 && other.y0 < self.y1
    }

    /// An error unless the rectangle is non-empty and inside a `width` x
    /// `height` image.
    pub fn check_inside(&self, width: u32, height: u32) -> anyhow::Result<()> {
        anyhow::ensure!(
            self.x0 < self.x1 && self.y0 < self.y1,
            "region {self} is empty (it needs x0 < x1 and y0 < y1)"
        );
        anyhow::ensure!(
            self.x1 <= width && self.y1 <= height,
            "region {self} reaches outside the {width}x{height} image"
        );
        Ok(())
    }

    /// Parses `X0,Y0,X1,Y1` (the form `Display` writes).
    pub fn parse(text: &str) -> Option<Region> {
        let v: Vec<u32> = text
            .split(',')
            .map(|p| p.trim().parse().ok())
            .collect::<Option<_>>()?;
        match v.as_slice() {
            &[x0, y0, x1, y1] => Some(Region { x0, y0, x1, y1 }),
            _ => None,
        }
    }
}

impl fmt::Display for Region {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn region_parses_checks_and_overlaps() {
        let r = Region::parse(" 2, 3,10,7").expect("parses");
        assert_eq!((r.width(), r.height(), r.pixel_count()), (8, 4, 32));
        assert_eq!(Region::parse(&r.to_string()), Some(r));
        assert_eq!(Region::parse("1,2,3"), None);
        assert_eq!(Region::parse("1,2,3,x"), None);
        assert!(r.check_inside(10, 7).is_ok());
        assert!(r.check_inside(9, 7).is_err());
        assert!(
            Region::parse("3,3,3,5")
                .unwrap()
                .check_inside(9, 9)
                .is_err()
        );
        // Half-open: touching edges do not overlap.
        let right = Region::parse("10,3,12,7").unwrap();
        assert!(!r.overlaps(&right));
        assert!(r.overlaps(&Region::parse("9,6,12,9").unwrap()));
        assert!(Region::full(4, 4).is_full(4, 4));
    }
}
