// The liner-material table: what each liner loses per joule by sliding and by impact.
//
// Wear of a liner = sliding wear + impact wear, each linear in an energy the wall records keep
// per triangle (the "shear and impact energy" split of DEM liner-wear studies: Kalala, Bwalya &
// Moys 2005, Minerals Engineering 18(15):1386-1391):
//
//   sliding: V_s = k_s W_f,  W_f = sum |F_t . v_slip| dt     (Archard 1953, J. Appl. Phys. 24:981)
//   impact:  V_i = K_i E_n,  E_n = sum 1/2 m* v_n^2          (Bitter 1963, Wear 6:5-21, deformation wear)
//
// Sliding. Archard's V = (k/H) F_n s; the friction work of that sliding is mu F_n s, so per
// friction work k_s = (k/H) / mu. A value measured as volume over normal load x distance (ASTM
// G65-16 Procedure A: 130 N over 6000 turns of a 228.6 mm wheel, 4309 m, so F_n s = 5.60e5 N m)
// is divided by the friction coefficient mu of rock on that liner named in the row (rock on steel
// 0.45 and on rubber 0.7, as the wall pairs of materials/gravel.yaml). A case whose wall friction
// differs from that mu changes the friction work but not the wear: the depth it gives is then
// off by mu_case / mu_row.
//
// Impact. Bitter's deformation wear W_D = M (V sin(alpha) - K)^2 / (2 epsilon), with the elastic
// limit velocity K set to 0 (an upper bound: K is below 1 m/s for steels, so (1 - K/v)^2 >= 0.64
// at 5 m/s), is a volume per normal impact energy, K_i = 1/epsilon. It is the law chosen because
// it needs exactly what the records keep: the normal kinetic energy of each impact, summed. The
// tangential part of an oblique impact is friction work during the contact and is already in
// the sliding term. Rejected alternatives:
//  - Finnie (1960, Wear 3:87-103): cutting by the tangential motion of an oblique impact; zero
//    at normal incidence, needs each impact's angle (not recorded), and would count the
//    sliding the Archard term already has a second time.
//  - Oka, Okamura & Yoshida (2005, Wear 259:95-101) in full: an angle function and a velocity
//    exponent k2 = 2.3 Hv^0.038 (2.3-2.5 for steels) that need each impact's speed and angle.
//    Its normal-incidence part is used below to give the steels' K_i.
//  - Hutchings (1981, Wear 70:269-281), normal incidence by a critical plastic strain: velocity
//    exponent 3 and a ductility to calibrate per material.
// The steels' K_i is Oka's normal-incidence erosion E90 = 65 Hv^-0.12 (v / 104 m/s)^k2 [mm^3 per
// kg of SiO2 particles], Hv in GPa, at the reference size D' = 326 um, divided by 1/2 v^2 at
// v = 5 m/s (a 1.3 m drop, the transfer chute's impact speed). Per joule it varies as
// v^(k2 - 2): -16 to -21 % at 3 m/s, +27 to +37 % at 10 m/s. Oka's size term (D/D')^0.19 is
// left out: 40 mm rock lies far outside the tests, where it would raise E90 about 2.5 times.
#include "case/liner_materials.h"

#include <algorithm>
#include <iterator>

namespace dem {

namespace {

// Rows: key, name, sliding [m^3/J], impact [m^3/J], sliding source, impact source, note.
constexpr LinerMaterial kLinerMaterials[] = {
    {"mild_steel", "Mild steel plate (S235/S355, about 150 HBW)", 1.0e-12, 4.1e-12,
     "ASTM G65 Procedure A: about 250 mm^3 for low-carbon structural steel; 250 / 5.60e5 / 0.45 mm^3/(N m)",
     "Oka et al. (2005) E90 at Hv = 1.54 GPa (157 HV), v = 5 m/s: 0.051 mm^3/kg over 12.5 J/kg",
     "estimate: the G65 volume is the order of published comparisons, not one test"},
    {"ar400", "AR400 wear plate (400 HBW, e.g. Hardox 400)", 4.4e-13, 2.8e-12,
     "ASTM G65 Procedure A: about 110 mm^3 for 400 HBW quenched wear plate; 110 / 5.60e5 / 0.45 mm^3/(N m)",
     "Oka et al. (2005) E90 at Hv = 4.1 GPa (400 HBW by ASTM E140), v = 5 m/s: 0.035 mm^3/kg over 12.5 J/kg",
     "estimate: the G65 volume is the order of published values for the grade (about 2.3 times the life of mild steel)"},
    {"ar500", "AR500 wear plate (500 HBW, e.g. Hardox 500)", 3.4e-13, 2.5e-12,
     "ASTM G65 Procedure A: about 85 mm^3 for 500 HBW quenched wear plate; 85 / 5.60e5 / 0.45 mm^3/(N m)",
     "Oka et al. (2005) E90 at Hv = 5.2 GPa (500 HBW by ASTM E140), v = 5 m/s: 0.032 mm^3/kg over 12.5 J/kg",
     "estimate: the G65 volume is the order of published values for the grade; brittle under heavy lumps"},
    {"alumina", "Alumina ceramic tiles (92-96 % Al2O3)", 6.0e-14, 2.5e-12,
     "ASTM G65 Procedure A: about 15 mm^3 for 92-96 % alumina; 15 / 5.60e5 / 0.45 mm^3/(N m)",
     "set to AR500's: tiles chip and crack under lumps, which no energy law predicts",
     "estimate (both): use where sliding dominates; the impact value is a conservative stand-in, not a measurement"},
    {"rubber", "Natural rubber lining (40-60 Shore A)", 2.9e-13, 5.0e-13,
     "about 2e-4 mm^3/(N m) against rounded rock (as AR400), over mu = 0.7: 2e-4 / 0.7; ISO 4649 losses "
     "(corundum paper) are not comparable with G65",
     "one-eighth of mild steel's at 5 m/s: rubber erodes at normal incidence by fatigue cracking, falling faster with "
     "speed than metals (Arnold & Hutchings 1990, Wear 138:33-46)",
     "estimate (both): sharp lumps over about 50 mm cut rubber, which neither law covers"},
    {"uhmwpe", "UHMW polyethylene liner", 1.2e-12, 1.0e-12,
     "about 3e-4 mm^3/(N m) against rock over mu = 0.25: 3e-4 / 0.25; sold for sliding of fines and sticky "
     "material, it wears faster under dry lumpy rock",
     "a quarter of mild steel's: no published energy coefficient at chute impact speeds",
     "estimate (both); with a wall friction mu other than 0.25 the sliding depth is off by mu / 0.25"},
};

}  // namespace

std::span<const LinerMaterial> liner_materials() { return kLinerMaterials; }

const LinerMaterial* find_liner_material(std::string_view key) {
  const auto it = std::find_if(std::begin(kLinerMaterials), std::end(kLinerMaterials),
                               [key](const LinerMaterial& m) { return key == m.key; });
  return it == std::end(kLinerMaterials) ? nullptr : &*it;
}

std::vector<std::string> liner_material_keys() {
  std::vector<std::string> keys;
  for (const LinerMaterial& m : kLinerMaterials) keys.emplace_back(m.key);
  return keys;
}

}  // namespace dem
