//! Inputs and expected scores for the firmware example, computed in float64 by
//! `python3 tools/firmware_expected.py` from `tables/default.mlmap` and `tests/golden/layer/small_open.mlmap`.
//! Generated: do not edit; `.ci/firmware.sh` checks that it is up to date.

use crate::case::{Case, ErrorCase, Expect, MapCase, OpenExpect, QCase, SetCase, WindowCase};
use mlmap::InferError;

/// Number of classes of the table.
pub const K: usize = 3;
/// The classes, in order: "car", "cyclist", "pedestrian".
pub const CLASS_NAMES: [&str; K] = ["car", "cyclist", "pedestrian"];
/// CRC-32 of the table the values were computed from (its last four bytes).
pub const TABLE_CRC: u32 = 0x8d1d2417;
/// The open head's temperature and epsilon stored in that table.
pub const OPEN_PARAMS: (f32, f32) = (1.0, 0.0);

/// Valid detections and their float64 ML, MAP, Bayes and open-head scores.
pub static CASES: &[Case<K>] = &[
    Case {
        label: "inside ML bin 0 of every class",
        logits: [0.09306364, -6.746873, -6.31205],
        objectness: 1.0,
        ml: Expect {
            scores: [0.31833455845905556, 0.3314334775583502, 0.3502319639825942],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.3336447477149684, 0.33317764812839257, 0.333177604156639],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.14101317897726148, 0.012859485009458632, 0.01318385774679128],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.1666028199556952, 0.00017829355825799785, 0.00027540821955819404],
            decision: 0,
        },
    },
    Case {
        label: "inside ML bin 11 of every class",
        logits: [4.8508635, 0.24092698, 0.4056499],
        objectness: 1.0,
        ml: Expect {
            scores: [0.7029691675770814, 0.19859512721422942, 0.09843570520868916],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.9323755789243818, 0.052091489283691554, 0.015532931791926686],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.2887471581300527, 0.01823334633559146, 0.013491916303440198],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.3136698470267275, 0.003121783628913896, 0.0036807901134429484],
            decision: 0,
        },
    },
    Case {
        label: "inside ML bin 21 of every class",
        logits: [9.176136, 6.5934725, 6.51265],
        objectness: 1.0,
        ml: Expect {
            scores: [0.27955380975351096, 0.3350396747331655, 0.38540651551332356],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.26413407440277487, 0.3204168876030338, 0.4154490379941914],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.29394205637129217, 0.16745261287464122, 0.3050544026369569],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.669225788221726, 0.05057502959350347, 0.046648254067660676],
            decision: 0,
        },
    },
    Case {
        label: "on inner ML edge 1 of every class",
        logits: [0.30932727, -6.4292455, -6.0067],
        objectness: 0.9,
        ml: Expect {
            scores: [0.26955976960464684, 0.27232059347160587, 0.3581196130818894],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.3005580854146602, 0.2997209879410242, 0.29972090280245767],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.12380532534259137, 0.01364540107126625, 0.015399095425845442],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.1523939437935306, 0.0001804856793857216, 0.00027539236678672584],
            decision: 0,
        },
    },
    Case {
        label: "on inner ML edge 7 of every class",
        logits: [2.904491, -2.6177182, -2.3425002],
        objectness: 0.9,
        ml: Expect {
            scores: [0.7296012780376697, 0.0746626546536225, 0.09573604346684986],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.8851610688016616, 0.00798462052720306, 0.006854286829277404],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.7906696850446393, 1.7322363641790336e-05, 3.491664453774115e-05],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.7834667560975331, 0.003131522986657607, 0.0041236449686281275],
            decision: 0,
        },
    },
    Case {
        label: "on inner ML edge 21 of every class",
        logits: [8.959872, 6.2758446, 6.2073],
        objectness: 0.9,
        ml: Expect {
            scores: [0.25159842211307765, 0.3015356992718806, 0.3468658547731838],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.21566744858833634, 0.2872125980656827, 0.3971199295041229],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.26454784372603823, 0.1507073475947957, 0.27454895510019744],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.6093400571035456, 0.041610345493846304, 0.038853743823639375],
            decision: 0,
        },
    },
    Case {
        label: "on inner MAP edge 1 of every class",
        logits: [0.4365412, -6.242406, -5.8270826],
        objectness: 0.8,
        ml: Expect {
            scores: [0.23960869401092974, 0.24206275977202785, 0.31832855813797134],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.26914524578459625, 0.26542729260049075, 0.26542747353584195],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.19980021221743627, 0.0007516557464325429, 0.0029502729274403275],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.2028608099951126, 0.0002550165045263867, 0.0003863143916701781],
            decision: 0,
        },
    },
    Case {
        label: "on inner MAP edge 8 of every class",
        logits: [4.3547297, -0.4877472, -0.29485893],
        objectness: 0.8,
        ml: Expect {
            scores: [0.6903421791408845, 0.07251520485460394, 0.03714262792544049],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.7724146705228209, 0.021303614930242857, 0.00628172646786527],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.48848484209174065, 0.0006378972298290424, 0.0005072364021690859],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.48123103588886035, 0.0037957067830229905, 0.004603233051855501],
            decision: 0,
        },
    },
    Case {
        label: "on the first ML edge of every class",
        logits: [-0.1232, -7.0645, -6.6174],
        objectness: 1.0,
        ml: Expect {
            scores: [0.31833455845905556, 0.3314334775583502, 0.3502319639825942],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.3334840645441536, 0.3332579772074441, 0.3332579582484023],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.14101317897726148, 0.012859485009458632, 0.01318385774679128],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.16664338012806826, 0.0001611461156505475, 0.0002519954897926028],
            decision: 0,
        },
    },
    Case {
        label: "on the closed last ML edge of every class",
        logits: [9.3924, 6.9111, 6.818],
        objectness: 1.0,
        ml: Expect {
            scores: [0.27955380975351096, 0.3350396747331655, 0.38540651551332356],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.28494858625062486, 0.322631596842139, 0.3924198169072361],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.29394205637129217, 0.16745261287464122, 0.3050544026369569],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.6608265403663426, 0.05526785790790637, 0.05035467360864113],
            decision: 0,
        },
    },
    Case {
        label: "on the closed last MAP edge of every class",
        logits: [9.3924, 6.9111, 6.818],
        objectness: 0.75,
        ml: Expect {
            scores: [0.20966535731513322, 0.2512797560498741, 0.2890548866349927],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.21371143968796866, 0.24197369763160426, 0.29431486268042706],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.22045654227846911, 0.12558945965598092, 0.22879080197771767],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.49561990527475697, 0.041450893430929774, 0.03776600520648086],
            decision: 0,
        },
    },
    Case {
        label: "class 0 one ulp above its last ML edge",
        logits: [9.392401, -4.8411093, -4.47995],
        objectness: 1.0,
        ml: Expect {
            scores: [0.25269566606648425, 0.33532996076942767, 0.4119743731640881],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.3331896292845227, 0.33343251248717476, 0.33337785822830246],
            uniform: false,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.9024117618999465, 0.00323534708476825, 0.004580923309840837],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.9102265731033516, 5.992591189807842e-07, 8.599320849730973e-07],
            decision: 0,
        },
    },
    Case {
        label: "class 0 one ulp below its first ML edge",
        logits: [-0.12320001, -4.8411093, -4.47995],
        objectness: 1.0,
        ml: Expect {
            scores: [0.25269566606648425, 0.33532996076942767, 0.4119743731640881],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.3331896292845227, 0.33343251248717476, 0.33337785822830246],
            uniform: false,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.15269829951292604, 0.004751919773835583, 0.006684894885177962],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.16064056770069102, 0.0014351366934802435, 0.0020594097777683314],
            decision: 0,
        },
    },
    Case {
        label: "only class 0 in support, at its mean",
        logits: [4.276356, -10000.0, -10000.0],
        objectness: 0.6,
        ml: Expect {
            scores: [0.5615834035065982, 0.01920831016762984, 0.01920831016762984],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.5979664194432056, 0.0010168021993261665, 0.0010168021993261665],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.5655291848502995, 0.0002966212132498345, 0.0005642560609362839],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.5663900621244856, 0.0, 0.0],
            decision: 0,
        },
    },
    Case {
        label: "class 1 one ulp above its last ML edge",
        logits: [1.3906454, 6.9111004, -4.47995],
        objectness: 1.0,
        ml: Expect {
            scores: [0.45240991175250583, 0.2081839618365948, 0.3394061264108994],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.4695598290870662, 0.2651451911697069, 0.26529497974322686],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.476517687999569, 0.0035401571540012704, 0.00020644391560894777],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.0019153000030019138, 0.478343585634687, 5.4034314902925325e-06],
            decision: 1,
        },
    },
    Case {
        label: "class 1 one ulp below its first ML edge",
        logits: [1.3906454, -7.0645003, -4.47995],
        objectness: 1.0,
        ml: Expect {
            scores: [0.45240991175250583, 0.2081839618365948, 0.3394061264108994],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.4695598290870662, 0.2651451911697069, 0.26529497974322686],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.5678539459878702, 0.0005372473209509332, 0.0001368731946608705],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.5668083722556669, 0.00012061827913793258, 0.0015990759686771963],
            decision: 0,
        },
    },
    Case {
        label: "only class 1 in support, at its mean",
        logits: [-10000.0, 2.3360717, -10000.0],
        objectness: 0.6,
        ml: Expect {
            scores: [0.017173236283208673, 0.5656535512754406, 0.017173236283208673],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.0012602268925535527, 0.5974795700567509, 0.0012602268925535527],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.010593986410893, 0.3253177435189333, 0.17389843009478967],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.0, 0.5098101600246159, 0.0],
            decision: 1,
        },
    },
    Case {
        label: "class 2 one ulp above its last ML edge",
        logits: [1.3906454, -4.8411093, 6.8180003],
        objectness: 1.0,
        ml: Expect {
            scores: [0.4829021356990478, 0.2948823973591542, 0.22221546694179797],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.4695394075542417, 0.26532693265264995, 0.26513365979310843],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.45486323142638957, 0.00021566595229361785, 0.0038933941155603257],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.0020082048848783706, 3.948129211195709e-06, 0.45696013848015404],
            decision: 2,
        },
    },
    Case {
        label: "class 2 one ulp below its first ML edge",
        logits: [1.3906454, -4.8411093, -6.6174006],
        objectness: 1.0,
        ml: Expect {
            scores: [0.4829021356990478, 0.2948823973591542, 0.22221546694179797],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.4695394075542417, 0.26532693265264995, 0.26513365979310843],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.6613078633501734, 0.00017305521176072484, 0.0003878987953446466],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.6603508203762702, 0.0012982491892118413, 0.00021974779179678738],
            decision: 0,
        },
    },
    Case {
        label: "only class 2 in support, at its mean",
        logits: [-10000.0, -10000.0, 2.866103],
        objectness: 0.6,
        ml: Expect {
            scores: [0.013645453461991627, 0.013645453461991627, 0.5727091169178746],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.0012740288597111404, 0.0012740288597111404, 0.5974519661224356],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.006570559098505536, 0.038077328659915054, 0.4705631270932521],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.0, 0.0, 0.5152110148516726],
            decision: 2,
        },
    },
    Case {
        label: "far above every support",
        logits: [109.3924, 109.3924, 109.3924],
        objectness: 0.7,
        ml: Expect {
            scores: [0.23333332935969034, 0.23333332935969034, 0.23333332935969034],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.23333332935969034, 0.23333332935969034, 0.23333332935969034],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.3905649933487171, 0.05837999900579447, 0.1110549981087449],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.18666666348775215, 0.18666666348775215, 0.18666666348775215],
            decision: 0,
        },
    },
    Case {
        label: "far below every support",
        logits: [-109.3924, -109.3924, -109.3924],
        objectness: 0.7,
        ml: Expect {
            scores: [0.23333332935969034, 0.23333332935969034, 0.23333332935969034],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.23333332935969034, 0.23333332935969034, 0.23333332935969034],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.3905649933487171, 0.05837999900579447, 0.1110549981087449],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.18666666348775215, 0.18666666348775215, 0.18666666348775215],
            decision: 0,
        },
    },
    Case {
        label: "alternating far outside",
        logits: [-109.3924, 109.3924, -109.3924],
        objectness: 1.0,
        ml: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.5579499999999992, 0.08339999999999992, 0.1586500000000004],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [7.692301921048765e-96, 0.7999999999999994, 7.692301921048765e-96],
            decision: 1,
        },
    },
    Case {
        label: "+inf everywhere",
        logits: [f32::INFINITY, f32::INFINITY, f32::INFINITY],
        objectness: 1.0,
        ml: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.5579499999999992, 0.08339999999999992, 0.1586500000000004],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.26666666666666644, 0.26666666666666644, 0.26666666666666644],
            decision: 0,
        },
    },
    Case {
        label: "-inf everywhere",
        logits: [f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY],
        objectness: 0.5,
        ml: Expect {
            scores: [0.16666666666666666, 0.16666666666666666, 0.16666666666666666],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.16666666666666666, 0.16666666666666666, 0.16666666666666666],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.2789749999999996, 0.04169999999999996, 0.0793250000000002],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.13333333333333322, 0.13333333333333322, 0.13333333333333322],
            decision: 0,
        },
    },
    Case {
        label: "largest finite values",
        logits: [-3.4e+38, 3.4e+38, -3.4e+38],
        objectness: 1.0,
        ml: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.5579499999999992, 0.08339999999999992, 0.1586500000000004],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.0, 0.7999999999999994, 0.0],
            decision: 1,
        },
    },
    Case {
        label: "+inf in class 0, others inside",
        logits: [f32::INFINITY, -3.5706, -3.2585502],
        objectness: 1.0,
        ml: Expect {
            scores: [0.15376071002195632, 0.47220996698023393, 0.3740293229978097],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.3232631449680719, 0.34615764535197285, 0.33057920967995524],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.828893716742028, 0.00568200670646271, 0.007705444996899509],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.8422811684453904, 0.0, 0.0],
            decision: 0,
        },
    },
    Case {
        label: "-inf in the last class, others inside",
        logits: [2.2557, -3.5706, f32::NEG_INFINITY],
        objectness: 0.9,
        ml: Expect {
            scores: [0.5448804400696937, 0.26788952034214125, 0.0872300157463071],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.838886684404625, 0.031601697286682176, 0.029511594466834858],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.6418173994249811, 0.00015096807795356623, 0.0015413331044763707],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.6416175911350999, 0.0018921094723112972, 0.0],
            decision: 0,
        },
    },
    Case {
        label: "objectness 0.0",
        logits: [4.276356, 2.3360717, 2.866103],
        objectness: 0.0,
        ml: Expect {
            scores: [0.0, 0.0, 0.0],
            uniform: false,
            argmax: None,
        },
        map: Expect {
            scores: [0.0, 0.0, 0.0],
            uniform: false,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.0, 0.0, 0.0],
            uniform: false,
            argmax: None,
        },
        open: OpenExpect {
            scores: [0.0, 0.0, 0.0],
            decision: 0,
        },
    },
    Case {
        label: "objectness 1.0",
        logits: [4.276356, 2.3360717, 2.866103],
        objectness: 1.0,
        ml: Expect {
            scores: [0.28072791268282987, 0.3162706306465886, 0.4030014566705815],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.3840840407892362, 0.30964228250415704, 0.3062736767066067],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.014184756891516598, 0.05925705048535051, 0.20578102951778857],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.20120622467962723, 0.02890590457875026, 0.04911070763627817],
            decision: 0,
        },
    },
    Case {
        label: "objectness 0.37",
        logits: [4.276356, 2.3360717, 2.866103],
        objectness: 0.37,
        ml: Expect {
            scores: [0.10386932903126206, 0.11702013484733367, 0.14911054088977585],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.14211109692347282, 0.11456764600302757, 0.11332126184187118],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.005248360117499333, 0.021925108962139325, 0.07613898190282219],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.07444630409088812, 0.01069518483197169, 0.018170962059601028],
            decision: 0,
        },
    },
    Case {
        label: "objectness 1e-06",
        logits: [4.276356, 2.3360717, 2.866103],
        objectness: 1e-06,
        ml: Expect {
            scores: [2.8072791197406004e-07, 3.1627062984808207e-07, 4.0300145565310066e-07],
            uniform: false,
            argmax: None,
        },
        map: Expect {
            scores: [3.840840398195172e-07, 3.0964228172238546e-07, 3.0627367593334e-07],
            uniform: false,
            argmax: None,
        },
        bayes: Expect {
            scores: [1.418475685570353e-08, 5.925705033574084e-08, 2.057810289982414e-07],
            uniform: false,
            argmax: None,
        },
        open: OpenExpect {
            scores: [2.0120622417163034e-07, 2.8905904505769868e-08, 4.911070751228555e-08],
            decision: 0,
        },
    },
    Case {
        label: "objectness 0, outside every support",
        logits: [109.3924, 109.3924, 109.3924],
        objectness: 0.0,
        ml: Expect {
            scores: [0.0, 0.0, 0.0],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.0, 0.0, 0.0],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.0, 0.0, 0.0],
            uniform: false,
            argmax: None,
        },
        open: OpenExpect {
            scores: [0.0, 0.0, 0.0],
            decision: 0,
        },
    },
    Case {
        label: "inside Bayes bin 0 of every logit",
        logits: [-8.327607, -8.127759, -7.9023666],
        objectness: 1.0,
        ml: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.4787230454602543, 0.04375341886718573, 0.13313755724337298],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.17477561062875924, 0.21343900505447777, 0.267399405887576],
            decision: 2,
        },
    },
    Case {
        label: "inside Bayes bin 11 of every logit",
        logits: [0.7384424, -0.43345928, -0.37101603],
        objectness: 1.0,
        ml: Expect {
            scores: [0.19118593210377202, 0.5348575321602917, 0.2739565357359362],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.05298798989146323, 0.8274062575081028, 0.11960575260043389],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.008028997919529485, 0.002445387255971787, 0.002008693827190511],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.007613886321731441, 0.0023586089677215165, 0.002510583713238826],
            decision: 0,
        },
    },
    Case {
        label: "inside Bayes bin 21 of every logit",
        logits: [8.980307, 6.5613585, 6.4756656],
        objectness: 1.0,
        ml: Expect {
            scores: [0.27955380975351096, 0.3350396747331655, 0.38540651551332356],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.26148506105292973, 0.3198308000859178, 0.41868413886115247],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.29394205637129217, 0.16745261287464122, 0.3050544026369569],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.6546817302982026, 0.058276623048792664, 0.05349071853589477],
            decision: 0,
        },
    },
    Case {
        label: "on inner Bayes edge 1 of every logit",
        logits: [-7.915514, -7.778018, -7.5600324],
        objectness: 0.9,
        ml: Expect {
            scores: [0.29999999205271405, 0.29999999205271405, 0.29999999205271405],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.29999999205271405, 0.29999999205271405, 0.29999999205271405],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.4862266738516696, 0.11030988538857829, 0.07869840193580636],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.18891576209349684, 0.21676139948627982, 0.26955779959627757],
            decision: 2,
        },
    },
    Case {
        label: "on inner Bayes edge 7 of every logit",
        logits: [-2.970396, -3.5811276, -3.452023],
        objectness: 0.9,
        ml: Expect {
            scores: [0.1383846353538197, 0.4249889590238476, 0.33662638178047477],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.29182814832487053, 0.3120633792833114, 0.2961084485499602],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.042799766717562235, 0.05886572286672199, 0.07964568808091091],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.08391196377274389, 0.04556029425640614, 0.05183891963604512],
            decision: 0,
        },
    },
    Case {
        label: "on the first Bayes edge of every logit",
        logits: [-8.7397, -8.4775, -8.2447],
        objectness: 1.0,
        ml: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.4787230454602543, 0.04375341886718573, 0.13313755724337298],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.16638746276151, 0.21626825038547756, 0.2729583084238255],
            decision: 2,
        },
    },
    Case {
        label: "on the closed last Bayes edge of every logit",
        logits: [9.3924, 6.9111, 6.818],
        objectness: 0.8,
        ml: Expect {
            scores: [0.22364305113534988, 0.26803174378051653, 0.30832521700506255],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.22795887239735177, 0.25810528131977956, 0.31393585820379766],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.2351536486010961, 0.13396209229590367, 0.24404352574609736],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.5286612401707403, 0.0442142869851693, 0.040283739487187394],
            decision: 0,
        },
    },
    Case {
        label: "one ulp outside every Bayes axis",
        logits: [-8.739701, 6.9111004, -8.244701],
        objectness: 1.0,
        ml: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.5579499999999992, 0.08339999999999992, 0.1586500000000004],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [1.276535821617469e-07, 0.7999996629309644, 2.0941545277997144e-07],
            decision: 1,
        },
    },
    Case {
        label: "one ulp outside every Bayes axis, objectness 0.25",
        logits: [9.392401, 6.9111004, 6.8180003],
        objectness: 0.25,
        ml: Expect {
            scores: [0.08333333333333333, 0.08333333333333333, 0.08333333333333333],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.08333333333333333, 0.08333333333333333, 0.08333333333333333],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.1394874999999998, 0.02084999999999998, 0.0396625000000001],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.17243848496470146, 0.0144217893173565, 0.013139725717941865],
            decision: 0,
        },
    },
    Case {
        label: "logit 0 below its Bayes axis, others inside",
        logits: [-8.739701, -0.43345928, -0.37101603],
        objectness: 1.0,
        ml: Expect {
            scores: [0.1771765719881904, 0.544121727821545, 0.2787017001902646],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.05135884923629773, 0.8288296409056273, 0.11981150985807489],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.18180826112006226, 0.06766075214565707, 0.05380176442467864],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [3.627626256395836e-05, 0.14688505081897732, 0.15634945060885672],
            decision: 2,
        },
    },
    Case {
        label: "test.csv id 25001 (background)",
        logits: [2.6283, -3.7759, -3.7148],
        objectness: 0.6091,
        ml: Expect {
            scores: [0.4219950552284012, 0.11389291998329093, 0.07321200895731422],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.5840353630174463, 0.012783673229358642, 0.012280947922201448],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.49392940948211866, 5.218358035702415e-05, 4.024168632820896e-05],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.49234125971461706, 0.0008146247141061194, 0.0008659503200806622],
            decision: 0,
        },
    },
    Case {
        label: "test.csv id 25002 (pedestrian)",
        logits: [-1.5155, -2.1577, 4.7103],
        objectness: 0.7606,
        ml: Expect {
            scores: [0.0399001773880985, 0.07034504956499932, 0.6503547438644681],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.008248931413928684, 0.013195850935153224, 0.739155188468484],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.00025984022606290885, 0.0015282907723322304, 0.6370638759354834],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.0012596818096324595, 0.0006627609212186672, 0.6369295642030273],
            decision: 2,
        },
    },
    Case {
        label: "test.csv id 25003 (cyclist)",
        logits: [-4.5564, 4.2786, 1.5954],
        objectness: 0.9668,
        ml: Expect {
            scores: [0.026315162471930033, 0.5311623916586264, 0.4093224203109718],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.0031974065763979258, 0.4492516430547823, 0.5143509248103482],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [4.303319133433639e-06, 0.6750538474064436, 0.26738343972486717],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.00012837852032038507, 0.8820315701633568, 0.060281641766766855],
            decision: 1,
        },
    },
    Case {
        label: "test.csv id 25004 (cyclist)",
        logits: [-5.2637, 2.7016, -3.642],
        objectness: 0.8178,
        ml: Expect {
            scores: [0.020756169207599956, 0.7560684755411242, 0.04097534066005881],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.0017568890350236836, 0.8142749540816631, 0.001768142292096222],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.00032021718728819523, 0.7409789910885818, 0.02205894191531674],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.00026456301310766843, 0.7617544517173288, 0.0013391354607503526],
            decision: 1,
        },
    },
    Case {
        label: "test.csv id 25005 (car)",
        logits: [1.6454, -4.9396, -3.7251],
        objectness: 0.8827,
        ml: Expect {
            scores: [0.475301023326228, 0.16376860922262257, 0.2436303934864583],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.6276925952910957, 0.1272054465258569, 0.12780198421835615],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.5130814078461192, 0.00015237643217666446, 0.00014798590938541918],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.5103032475924368, 0.0007046916934939616, 0.002373830901750562],
            decision: 0,
        },
    },
    Case {
        label: "test.csv id 25006 (car)",
        logits: [1.5308, -2.0375, -4.4045],
        objectness: 0.9384,
        ml: Expect {
            scores: [0.3663472676707246, 0.29721233395794855, 0.27484036890279046],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.436179450584012, 0.2892806530700389, 0.21293986687741276],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.4043306219973389, 0.00020531735791440991, 0.00011515105848113573],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.39254188312116334, 0.01107115802500159, 0.00103804926756951],
            decision: 0,
        },
    },
    Case {
        label: "test.csv id 25007 (background)",
        logits: [3.9984, -4.2986, -3.707],
        objectness: 0.3099,
        ml: Expect {
            scores: [0.26826242456229055, 0.022918685414053508, 0.018718875813908634],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.3088086331690662, 0.000547187470204615, 0.0005441651509819451],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.30387750533328595, 3.905960129149266e-06, 6.0676467924322245e-06],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.30367501212106146, 7.569508263364129e-05, 0.00013677173651239677],
            decision: 0,
        },
    },
    Case {
        label: "test.csv id 25008 (pedestrian)",
        logits: [-2.3733, -3.813, 3.9806],
        objectness: 0.8863,
        ml: Expect {
            scores: [0.027894187777252447, 0.08566501473202051, 0.7727408248611799],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.002811018685181924, 0.002900537693041106, 0.8805884709922299],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.00011831176191749637, 0.0034503574292867787, 0.8256756420374969],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.0014397429964820136, 0.0003412174692489389, 0.8274633507629702],
            decision: 2,
        },
    },
    Case {
        label: "test.csv id 25009 (background)",
        logits: [3.4216, -3.4924, -3.6607],
        objectness: 0.675,
        ml: Expect {
            scores: [0.5548799589665759, 0.07311845634949389, 0.0470015966048591],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.6709298748491284, 0.002109748423956479, 0.001960388647844232],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.6292897576405663, 2.243536949810182e-05, 1.9710167369705066e-05],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.628180063518208, 0.0006242694558083907, 0.0005275702034177099],
            decision: 0,
        },
    },
    Case {
        label: "test.csv id 25010 (car)",
        logits: [4.2784, -2.2393, -2.689],
        objectness: 0.7741,
        ml: Expect {
            scores: [0.6899623870814471, 0.04160629316639261, 0.042531325378838795],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.7706876905326756, 0.0020034776150249156, 0.0014088374789779628],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.737323467146942, 1.0632209300664856e-05, 2.1431317369793472e-05],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.7355760531532944, 0.001086491808280486, 0.0006929857120375124],
            decision: 0,
        },
    },
    Case {
        label: "test.csv id 25011 (car)",
        logits: [4.4131, -2.9186, -5.1224],
        objectness: 0.9002,
        ml: Expect {
            scores: [0.7766791677262473, 0.07868852218019547, 0.0448323194395655],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.8966926944306406, 0.0018908627839705136, 0.001616452131397271],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.8811642364151898, 1.7771709668179785e-05, 2.553870563768671e-05],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.8805676371030864, 0.000576296435047489, 6.36132923620983e-05],
            decision: 0,
        },
    },
    Case {
        label: "test.csv id 25012 (car)",
        logits: [5.836, -1.89, -3.0412],
        objectness: 0.8762,
        ml: Expect {
            scores: [0.6669412987157289, 0.08469672693278069, 0.12456199466475328],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.8537307385654677, 0.013089089837196335, 0.009380191910598926],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.86226933029453, 4.2442519378457036e-05, 6.448112175073197e-05],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.8618757284267686, 0.0003802642559129431, 0.00012026125297788131],
            decision: 0,
        },
    },
    Case {
        label: "test.csv id 25013 (car)",
        logits: [4.4407, -3.1612, -3.402],
        objectness: 0.7329,
        ml: Expect {
            scores: [0.618733573815274, 0.0626864123178792, 0.051480037327234926],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.7300311061350415, 0.0015270378831371727, 0.0013418794422094052],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.7104470339022856, 1.708877831472399e-05, 2.3174319949067618e-05],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.7098540298359369, 0.000354573101685546, 0.00027869406292681015],
            decision: 0,
        },
    },
    Case {
        label: "test.csv id 25014 (pedestrian)",
        logits: [-4.7499, -6.611, 2.7963],
        objectness: 0.8177,
        ml: Expect {
            scores: [0.018550491910344084, 0.020572564336127374, 0.7785769721730231],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.0017378042289123115, 0.0017378066994553903, 0.8142244174911268],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.00015287412440586538, 0.013572953862778297, 0.7586220836080071],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.0004076384143308701, 6.338836614014789e-05, 0.7718768848147202],
            decision: 2,
        },
    },
    Case {
        label: "test.csv id 25015 (car)",
        logits: [4.0221, -3.7995, -4.6135],
        objectness: 0.9311,
        ml: Expect {
            scores: [0.7984208860226911, 0.08666948385292016, 0.04600964099627589],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.9278103480356443, 0.0016710119105855902, 0.0016186509256574191],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.9119053402563204, 1.5018051645913841e-05, 1.688439368979084e-05],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.9114098585575983, 0.000365456776762323, 0.00016192736729537296],
            decision: 0,
        },
    },
    Case {
        label: "test.csv id 25016 (car)",
        logits: [4.5637, -3.9038, -3.603],
        objectness: 0.8961,
        ml: Expect {
            scores: [0.7790851991579238, 0.0644087928855347, 0.05260599260238491],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.8927453272762887, 0.001693236273369628, 0.0016614210961849374],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.8854658852591796, 1.692148614315698e-05, 2.08723198862832e-05],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.8850663295918709, 0.000186031806180491, 0.00025131766715745263],
            decision: 0,
        },
    },
];

/// Shape of `tests/golden/layer/small_open.mlmap`: ML bins, MAP bins, Bayes bins, Bayes categories.
pub const SMALL_SHAPE: (usize, usize, usize, usize) = (4, 2, 4, 4);
/// CRC-32 of that table.
pub const SMALL_TABLE_CRC: u32 = 0xdf983d8f;
/// Its open head's temperature and epsilon (an unknown category of weight epsilon).
pub const SMALL_OPEN_PARAMS: (f32, f32) = (1.75, 0.05);

/// Valid detections on that table and their float64 scores.
pub static SMALL_CASES: &[Case<K>] = &[
    Case {
        label: "inside Bayes bin 0 of every logit",
        logits: [-3.0, -1.5, -3.5],
        objectness: 1.0,
        ml: Expect {
            scores: [0.01470588190983788, 0.6029411802168252, 0.3823529378733369],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.010227764423320764, 0.055555663787531254, 0.934216571789148],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.30104894828357676, 0.11381118521359573, 0.1409090796291421],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.07651527561463077, 0.1803020065823847, 0.05749949219779217],
            decision: 1,
        },
    },
    Case {
        label: "inside Bayes bin 0 of logit 0, bin 3 of the others",
        logits: [-3.0, 1.5, -0.5],
        objectness: 0.9,
        ml: Expect {
            scores: [0.023684209318434284, 0.2605263113258328, 0.615789455513875],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.0133019339779533, 0.07225408615377288, 0.8144439560264158],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.0007092918613135791, 0.3077526450568561, 0.5624685085394874],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.045179843822121965, 0.5911558130199293, 0.18852346517223842],
            decision: 1,
        },
    },
    Case {
        label: "inside Bayes bin 1 of every logit",
        logits: [-1.0, -0.5, -2.5],
        objectness: 1.0,
        ml: Expect {
            scores: [0.01724137859053548, 0.5344827684211708, 0.44827585298829375],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.002770304518377817, 0.6731028641298267, 0.32412683135179554],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.2534046875084652, 0.2326555129905951, 0.1568695608586926],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.2204051417205043, 0.29329581046758685, 0.09353395719376184],
            decision: 1,
        },
    },
    Case {
        label: "inside Bayes bin 1 of logit 0, bin 2 of the others",
        logits: [-1.0, 0.5, -1.5],
        objectness: 0.9,
        ml: Expect {
            scores: [0.01874999899397761, 0.393749992843368, 0.4874999843207965],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.002792391791208469, 0.6784694245582932, 0.21873815980864045],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.12017340799738335, 0.27858380982316067, 0.27728322201505873],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.1580945030897613, 0.3725368027201942, 0.11880442923197627],
            decision: 1,
        },
    },
    Case {
        label: "inside Bayes bin 2 of every logit",
        logits: [1.0, 0.5, -1.5],
        objectness: 1.0,
        ml: Expect {
            scores: [0.30882353106333155, 0.30882353106333155, 0.3823529378733369],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.16064043424890737, 0.6347246852293001, 0.20463488052179252],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.2972602735690015, 0.10068493446891788, 0.12465753187535465],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.2542381786230184, 0.19105421826801688, 0.060928443010075696],
            decision: 0,
        },
    },
    Case {
        label: "inside Bayes bin 2 of logit 0, bin 1 of the others",
        logits: [1.0, -0.5, -2.5],
        objectness: 0.9,
        ml: Expect {
            scores: [0.24230768464880412, 0.3576923051878395, 0.29999998632149844],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.13131235856174558, 0.5188431906606843, 0.2498444269357122],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.3657136282588373, 0.04905914454526578, 0.041146378569213826],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.28284992950941756, 0.12003382948543624, 0.03827957532361296],
            decision: 0,
        },
    },
    Case {
        label: "inside Bayes bin 3 of every logit",
        logits: [3.0, 1.5, -0.5],
        objectness: 1.0,
        ml: Expect {
            scores: [0.5256410284270333, 0.14102564142364213, 0.33333333014932454],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.7324394435307876, 0.021802623417261708, 0.24575793305195076],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.0941498568900722, 0.35078417723866107, 0.4343041984001841],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.5081370883112227, 0.21563958216063323, 0.06876887676962701],
            decision: 0,
        },
    },
    Case {
        label: "inside Bayes bin 3 of logit 0, bin 0 of the others",
        logits: [3.0, -1.5, -3.5],
        objectness: 0.9,
        ml: Expect {
            scores: [0.3416666588372332, 0.3416666588372332, 0.2166666584836757],
            uniform: false,
            argmax: None,
        },
        map: Expect {
            scores: [0.5881094825908211, 0.0175063340598332, 0.29438415950748786],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.8553908574985346, 0.0027768725633058058, 0.0023289898506652583],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.7518116925554782, 0.05745817617826011, 0.01832378915512309],
            decision: 0,
        },
    },
    Case {
        label: "on Bayes edge 0 of every logit",
        logits: [-4.0, -2.0, -4.0],
        objectness: 0.8,
        ml: Expect {
            scores: [0.011764705703178077, 0.48235295136107914, 0.30588235485667176],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.01056453635210806, 0.011978390570057552, 0.7774570849987634],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.24083916221564453, 0.09104894952761164, 0.1127272653830808],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.04896171902818244, 0.1535299852064292, 0.04896171902818244],
            decision: 1,
        },
    },
    Case {
        label: "on Bayes edge 1 of every logit",
        logits: [-2.0, -1.0, -3.0],
        objectness: 0.8,
        ml: Expect {
            scores: [0.013793103077961633, 0.4275862211084677, 0.35862068773449957],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.004919729728636715, 0.2705406801450792, 0.5245396020472131],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.2027237530275914, 0.1861244131659459, 0.12549565055698497],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.14564114242766724, 0.25790059987780256, 0.08224619243881681],
            decision: 1,
        },
    },
    Case {
        label: "on Bayes edge 2 of every logit",
        logits: [0.0, 0.0, -2.0],
        objectness: 0.8,
        ml: Expect {
            scores: [0.15172414094493167, 0.28965517863471785, 0.35862069234127947],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.023419883942343775, 0.6460731609936736, 0.13050696698491157],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.2378082223988198, 0.08054794877539226, 0.0997260269863173],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.1746412233284883, 0.1746412233284883, 0.05569423129853488],
            decision: 0,
        },
    },
    Case {
        label: "on Bayes edge 3 of every logit",
        logits: [2.0, 1.0, -1.0],
        objectness: 0.8,
        ml: Expect {
            scores: [0.3647058947160066, 0.1294117656997228, 0.30588235150519955],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.5629613777812928, 0.10312158000926502, 0.13391705413037105],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.07531988663441151, 0.2806273459726021, 0.3474433638974568],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.3633841446780816, 0.20520961175000213, 0.06544269081298176],
            decision: 0,
        },
    },
    Case {
        label: "on Bayes edge 4 of every logit",
        logits: [4.0, 2.0, 0.0],
        objectness: 0.8,
        ml: Expect {
            scores: [0.420512829007756, 0.11282051482007036, 0.2666666680931026],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.36072752934966734, 0.009857122309539347, 0.4294153602617222],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.07531988663441151, 0.2806273459726021, 0.3474433638974568],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.44631345854921195, 0.14233228855328375, 0.04539070013856969],
            decision: 0,
        },
    },
    Case {
        label: "one ulp below every Bayes axis",
        logits: [-4.0000005, -2.0000002, -4.0000005],
        objectness: 1.0,
        ml: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.3999999999999996, 0.20000000000000015, 0.20000000000000015],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.00017705372314383335, 0.0005551900492457586, 0.00017705372314383335],
            decision: 1,
        },
    },
    Case {
        label: "one ulp above every Bayes axis",
        logits: [4.0000005, 2.0000002, 1e-45],
        objectness: 1.0,
        ml: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.3999999999999996, 0.20000000000000015, 0.20000000000000015],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.0006400763428915036, 0.00020412451512628654, 6.509663751563512e-05],
            decision: 0,
        },
    },
    Case {
        label: "logit 0 one ulp above its Bayes axis, others inside",
        logits: [4.0000005, -0.5, -2.5],
        objectness: 1.0,
        ml: Expect {
            scores: [0.01724137859053548, 0.5344827684211708, 0.44827585298829375],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.002770304518377817, 0.6731028641298267, 0.32412683135179554],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.47569061726537426, 0.09419889265447155, 0.07900552147592739],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.26627206695010674, 0.020350179861369156, 0.006489805800512833],
            decision: 0,
        },
    },
    Case {
        label: "logit 0 below its Bayes axis, others inside",
        logits: [-7.0, -0.5, -2.5],
        objectness: 0.7,
        ml: Expect {
            scores: [0.012068964807841587, 0.37413793152328845, 0.313793091747941],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.0019392131298398686, 0.4711719968668672, 0.22688877808236393],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.33298342641508794, 0.06593922373519177, 0.055303864091329966],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.003722815936619838, 0.15274442020089196, 0.04871119719671239],
            decision: 1,
        },
    },
    Case {
        label: "logit 1 one ulp above its Bayes axis, others inside",
        logits: [-1.0, 2.0000002, -2.5],
        objectness: 1.0,
        ml: Expect {
            scores: [0.035714285001538844, 0.035714285001538844, 0.9285714299969223],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.008403330687169754, 0.008403330687169754, 0.9831933386256605],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.13770491958658976, 0.4712369512093507, 0.1344262299022052],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.04612931267984975, 0.2561426327103478, 0.01957602769106965],
            decision: 1,
        },
    },
    Case {
        label: "logit 1 below its Bayes axis, others inside",
        logits: [-1.0, -5.0, -2.5],
        objectness: 0.7,
        ml: Expect {
            scores: [0.024999999075329737, 0.024999999075329737, 0.6499999899284116],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.005882331380843319, 0.005882331380843319, 0.6882353253173844],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.09639344206904227, 0.3298658602289633, 0.0940983593290581],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.14762950039586414, 0.015014125735436791, 0.06264995118885927],
            decision: 0,
        },
    },
    Case {
        label: "logit 2 one ulp above its Bayes axis, others inside",
        logits: [-1.0, -0.5, 1e-45],
        objectness: 1.0,
        ml: Expect {
            scores: [0.03030302859261241, 0.9393939428147752, 0.03030302859261241],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.004082120624326418, 0.9918357587513472, 0.004082120624326418],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.28364780181364685, 0.17641509393779237, 0.3352201208220103],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.08141042954602876, 0.10833385159632858, 0.1441611777156855],
            decision: 2,
        },
    },
    Case {
        label: "logit 2 below its Bayes axis, others inside",
        logits: [-1.0, -0.5, -7.0],
        objectness: 0.7,
        ml: Expect {
            scores: [0.021212119653588435, 0.6575757487718942, 0.021212119653588435],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.002857484388365822, 0.6942850193023393, 0.002857484388365822],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.1985534578882075, 0.12349056365342286, 0.23465408057927198],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.09890792730224074, 0.1316179852853275, 0.003207904632598496],
            decision: 1,
        },
    },
    Case {
        label: "outside every Bayes axis, objectness 1.0",
        logits: [-5.5, 3.5, -5.5],
        objectness: 1.0,
        ml: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.3999999999999996, 0.20000000000000015, 0.20000000000000015],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [5.249857472530809e-06, 0.0008987977805883635, 5.249857472530809e-06],
            decision: 1,
        },
    },
    Case {
        label: "outside every Bayes axis, objectness 0.37",
        logits: [-5.5, 3.5, -5.5],
        objectness: 0.37,
        ml: Expect {
            scores: [0.12333333492279053, 0.12333333492279053, 0.12333333492279053],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.12333333492279053, 0.12333333492279053, 0.12333333492279053],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.14800000190734847, 0.07400000095367437, 0.07400000095367437],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [1.9424472898696705e-06, 0.0003325551831034963, 1.9424472898696705e-06],
            decision: 1,
        },
    },
    Case {
        label: "outside every Bayes axis, objectness 1e-06",
        logits: [-5.5, 3.5, -5.5],
        objectness: 1e-06,
        ml: Expect {
            scores: [3.3333333249174757e-07, 3.3333333249174757e-07, 3.3333333249174757e-07],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [3.3333333249174757e-07, 3.3333333249174757e-07, 3.3333333249174757e-07],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [3.999999989900967e-07, 1.9999999949504868e-07, 1.9999999949504868e-07],
            uniform: false,
            argmax: None,
        },
        open: OpenExpect {
            scores: [5.249857459276192e-12, 8.987977783191173e-10, 5.249857459276192e-12],
            decision: 1,
        },
    },
    Case {
        label: "outside every Bayes axis, objectness 0.0",
        logits: [-5.5, 3.5, -5.5],
        objectness: 0.0,
        ml: Expect {
            scores: [0.0, 0.0, 0.0],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.0, 0.0, 0.0],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.0, 0.0, 0.0],
            uniform: false,
            argmax: None,
        },
        open: OpenExpect {
            scores: [0.0, 0.0, 0.0],
            decision: 1,
        },
    },
    Case {
        label: "+inf in logit 1, others inside",
        logits: [-1.0, f32::INFINITY, -2.5],
        objectness: 1.0,
        ml: Expect {
            scores: [0.035714285001538844, 0.035714285001538844, 0.9285714299969223],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.008403330687169754, 0.008403330687169754, 0.9831933386256605],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.13770491958658976, 0.4712369512093507, 0.1344262299022052],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.0, 0.3218479730812672, 0.0],
            decision: 1,
        },
    },
    Case {
        label: "+inf in logits 0 and 2",
        logits: [f32::INFINITY, -0.5, f32::INFINITY],
        objectness: 0.6,
        ml: Expect {
            scores: [0.018181817878047946, 0.563636388085762, 0.018181817878047946],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.0024492724719211902, 0.5951014788980156, 0.0024492724719211902],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.3280000171803927, 0.04400000166882952, 0.10400000127823382],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.00785651399267876, 0.0, 0.00785651399267876],
            decision: 0,
        },
    },
    Case {
        label: "+inf everywhere",
        logits: [f32::INFINITY, f32::INFINITY, f32::INFINITY],
        objectness: 1.0,
        ml: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.3999999999999996, 0.20000000000000015, 0.20000000000000015],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.0003030991651778084, 0.0003030991651778084, 0.0003030991651778084],
            decision: 0,
        },
    },
    Case {
        label: "-inf everywhere",
        logits: [f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY],
        objectness: 0.5,
        ml: Expect {
            scores: [0.16666666666666666, 0.16666666666666666, 0.16666666666666666],
            uniform: true,
            argmax: None,
        },
        map: Expect {
            scores: [0.16666666666666666, 0.16666666666666666, 0.16666666666666666],
            uniform: true,
            argmax: None,
        },
        bayes: Expect {
            scores: [0.1999999999999998, 0.10000000000000007, 0.10000000000000007],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.0001515495825889042, 0.0001515495825889042, 0.0001515495825889042],
            decision: 0,
        },
    },
    Case {
        label: "-inf in logit 0, others inside",
        logits: [f32::NEG_INFINITY, -0.5, -2.5],
        objectness: 0.9,
        ml: Expect {
            scores: [0.015517240320415434, 0.4810344788359915, 0.4034482570017352],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.002493274000490829, 0.6057925616688211, 0.2917141404888301],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.4281215441974887, 0.08477900114314778, 0.07110496744469623],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.0, 0.20001480688495435, 0.06378603347749957],
            decision: 1,
        },
    },
    Case {
        label: "tied largest logits 0 and 1",
        logits: [1.0, 1.0, -1.0],
        objectness: 1.0,
        ml: Expect {
            scores: [0.36206896789814924, 0.18965517335508225, 0.4482758587467685],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.3272685285805475, 0.2926659297819989, 0.3800655416374536],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.026004597468797963, 0.3639697039222123, 0.4506291354080692],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.3421583693509935, 0.3421583693509935, 0.10911654762930885],
            decision: 0,
        },
    },
    Case {
        label: "tied largest logits 1 and 2",
        logits: [-3.0, 0.5, 0.5],
        objectness: 0.8,
        ml: Expect {
            scores: [0.03478260808721156, 0.7304347957465058, 0.03478260808721156],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.003265696548123804, 0.7934686188246813, 0.003265696548123804],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.018260869313784203, 0.2830434900385067, 0.3504347802150979],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.012191854564652126, 0.09008629732821827, 0.09008629732821827],
            decision: 1,
        },
    },
    Case {
        label: "all logits equal",
        logits: [0.25, 0.25, 0.25],
        objectness: 1.0,
        ml: Expect {
            scores: [0.3333333333333333, 0.6363636373898871, 0.030303029276779542],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.05992366702804686, 0.9374212399529274, 0.00265509301902575],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.31911765046674323, 0.1595588252333713, 0.13382352847701406],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.09830068350018854, 0.09830068350018854, 0.09830068350018854],
            decision: 0,
        },
    },
    Case {
        label: "logits one ulp apart",
        logits: [1.5, 1.5000001, -2.0],
        objectness: 1.0,
        ml: Expect {
            scores: [0.36206896789814924, 0.18965517335508225, 0.4482758587467685],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.5079778670218416, 0.030997201640170436, 0.461024931337988],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.021436535649429652, 0.3000334668822509, 0.1887798268749675],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.22779188201524087, 0.22779189753233192, 0.030828278871533683],
            decision: 1,
        },
    },
    Case {
        label: "grid point 0",
        logits: [-1.1903464, 1.3483442, -4.0091834],
        objectness: 0.8,
        ml: Expect {
            scores: [0.06153846069200503, 0.6769230905369189, 0.06153846069200503],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.059195806650237826, 0.6816083986204533, 0.059195806650237826],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.0037931032298816145, 0.5363793195715074, 0.18379310245398278],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.06803085845595377, 0.29022071713713055, 0.013588140312074526],
            decision: 1,
        },
    },
    Case {
        label: "grid point 1",
        logits: [0.6915085, -1.3182739, -4.7250786],
        objectness: 1.0,
        ml: Expect {
            scores: [0.20754716954608116, 0.7735849065887159, 0.018867923865202873],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.7514726700388591, 0.23120042825458959, 0.017326901706551275],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.608133969421859, 0.005023923193266839, 0.13062200795141432],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.2661547020141467, 0.08440533879296738, 0.012047836780645667],
            decision: 0,
        },
    },
    Case {
        label: "grid point 2",
        logits: [-3.912767, -0.9095083, -0.6270843],
        objectness: 0.55,
        ml: Expect {
            scores: [0.009482758430327762, 0.293965529003175, 0.24655172448742615],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.0038645453681538633, 0.29865067053189026, 0.24748479602088483],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.023181893160683135, 0.044238935974487685, 0.44837175340025],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.03669849656036015, 0.20415583229080267, 0.2399111660797072],
            decision: 2,
        },
    },
    Case {
        label: "grid point 3",
        logits: [-2.4532516, 1.4283609, -4.9379344],
        objectness: 1.0,
        ml: Expect {
            scores: [0.07692307471876315, 0.8461538505624737, 0.07692307471876315],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.10264618594963223, 0.7947076281007356, 0.10264618594963223],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.0008620688488383453, 0.5521551857994446, 0.3474137784243993],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.029827671454237446, 0.2741021488982672, 0.007211073228620495],
            decision: 1,
        },
    },
    Case {
        label: "grid point 4",
        logits: [-1.4032651, -1.5638684, 0.84188145],
        objectness: 0.8,
        ml: Expect {
            scores: [0.018604650795298563, 0.7627907103303319, 0.018604650795298563],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.13341095910662346, 0.533178093707682, 0.13341095910662346],
            uniform: false,
            argmax: Some(1),
        },
        bayes: Expect {
            scores: [0.29333333978972076, 0.016585364950607032, 0.34666666540936714],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.04269519039928643, 0.03895133207126768, 0.15401148468263984],
            decision: 2,
        },
    },
    Case {
        label: "grid point 5",
        logits: [-3.4474, 1.801052, -0.8853883],
        objectness: 1.0,
        ml: Expect {
            scores: [0.02631578882872398, 0.28947368691935926, 0.6842105242519168],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.013904497128929421, 0.022348467256852956, 0.9637470356142176],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.0007881020890037746, 0.3419473924550192, 0.6249650260442386],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.03609583090068537, 0.724363137827393, 0.1560511911225823],
            decision: 1,
        },
    },
    Case {
        label: "grid point 6",
        logits: [-1.7031889, -2.5601723, -2.3547735],
        objectness: 1.0,
        ml: Expect {
            scores: [0.035714285001538844, 0.035714285001538844, 0.9285714299969223],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.00827715580633771, 0.00827715580633771, 0.9834456883873246],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.13770491958658976, 0.4712369512093507, 0.1344262299022052],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.13981650122961767, 0.08568056702914237, 0.09635090482250716],
            decision: 0,
        },
    },
    Case {
        label: "grid point 7",
        logits: [0.759822, -1.8817863, -3.3314178],
        objectness: 1.0,
        ml: Expect {
            scores: [0.14102564142364213, 0.5256410284270333, 0.33333333014932454],
            uniform: false,
            argmax: Some(1),
        },
        map: Expect {
            scores: [0.3246653295519708, 0.009178576789776554, 0.6661560936582527],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.8044303817258, 0.00981012584314461, 0.008227847336009217],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.5854705210679876, 0.12940219482891108, 0.05651830191916616],
            decision: 0,
        },
    },
    Case {
        label: "grid point 8",
        logits: [-2.098693, 1.9973804, -1.8644766],
        objectness: 1.0,
        ml: Expect {
            scores: [0.02631578882872398, 0.28947368691935926, 0.6842105242519168],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.012085739251564412, 0.013737408016996926, 0.9741768527314386],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.0010094430289608527, 0.4379843885725404, 0.40680557854286004],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.06299116801853537, 0.6543273905920399, 0.07201197543206872],
            decision: 1,
        },
    },
    Case {
        label: "grid point 9",
        logits: [2.964147, 2.2403202, -4.4805293],
        objectness: 0.8,
        ml: Expect {
            scores: [0.7515151654502686, 0.024242423235330178, 0.024242423235330178],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.791622247422112, 0.004188882249408494, 0.004188882249408494],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.5915151601666281, 0.05333333357574461, 0.05333333357574461],
            uniform: false,
            argmax: Some(0),
        },
        open: OpenExpect {
            scores: [0.015081638354649754, 0.009972812474272825, 0.0002142476267294078],
            decision: 0,
        },
    },
    Case {
        label: "grid point 10",
        logits: [-0.9515299, -2.7468498, -1.1260748],
        objectness: 1.0,
        ml: Expect {
            scores: [0.035714285001538844, 0.035714285001538844, 0.9285714299969223],
            uniform: false,
            argmax: Some(2),
        },
        map: Expect {
            scores: [0.013240911837830792, 0.013240911837830792, 0.9735181763243385],
            uniform: false,
            argmax: Some(2),
        },
        bayes: Expect {
            scores: [0.17554697140290926, 0.2756756780231295, 0.3271557241605199],
            uniform: false,
            argmax: Some(2),
        },
        open: OpenExpect {
            scores: [0.16136683479065497, 0.057845935393022324, 0.14604872865735125],
            decision: 0,
        },
    },
    Case {
        label: "grid point 11",
        logits: [2.8685687, 1.0980189, -2.6167064],
        objectness: 1.0,
        ml: Expect {
            scores: [0.45588236160183176, 0.16176470471417154, 0.38235293368399675],
            uniform: false,
            argmax: Some(0),
        },
        map: Expect {
            scores: [0.5757856300177543, 0.10272258481928391, 0.3214917851629618],
            uniform: false,
            argmax: Some(0),
        },
        bayes: Expect {
            scores: [0.05745682588353664, 0.46649472058421493, 0.07055393251477089],
            uniform: false,
            argmax: Some(1),
        },
        open: OpenExpect {
            scores: [0.384601886975268, 0.13983539926560626, 0.016739410763203826],
            decision: 0,
        },
    },
];

/// Scales of the quantized section of `tables/default_q8.mlmap`.
pub const Q_SCALES: [f32; K] = [0.08, 0.08, 0.08];
/// Zero points of that section.
pub const Q_ZERO_POINTS: [i32; K] = [0, 0, 0];

/// int8 codes, their dequantized logits and the float64 scores of those.
pub static QCASES: &[QCase<K>] = &[
    QCase {
        codes: [-128, -128, -128],
        case: Case {
            label: "every code -128",
            logits: [-10.24, -10.24, -10.24],
            objectness: 1.0,
            ml: Expect {
                scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
                uniform: true,
                argmax: None,
            },
            map: Expect {
                scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
                uniform: true,
                argmax: None,
            },
            bayes: Expect {
                scores: [0.5579499999999992, 0.08339999999999992, 0.1586500000000004],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.26666666666666644, 0.26666666666666644, 0.26666666666666644],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [127, 127, 127],
        case: Case {
            label: "every code 127",
            logits: [10.16, 10.16, 10.16],
            objectness: 0.8,
            ml: Expect {
                scores: [0.26666667064030963, 0.26666667064030963, 0.26666667064030963],
                uniform: true,
                argmax: None,
            },
            map: Expect {
                scores: [0.26666667064030963, 0.26666667064030963, 0.26666667064030963],
                uniform: true,
                argmax: None,
            },
            bayes: Expect {
                scores: [0.44636000665128167, 0.06672000099420541, 0.1269200018912557],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.21333333651224753, 0.21333333651224753, 0.21333333651224753],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [0, 0, 0],
        case: Case {
            label: "every code 0",
            logits: [0.0, 0.0, 0.0],
            objectness: 0.55,
            ml: Expect {
                scores: [0.060133604363787334, 0.40106289465360656, 0.08880351290353505],
                uniform: false,
                argmax: Some(1),
            },
            map: Expect {
                scores: [0.018398416086730988, 0.4237582992952902, 0.10784329653890783],
                uniform: false,
                argmax: Some(1),
            },
            bayes: Expect {
                scores: [0.0002917837299583599, 0.04013155227698078, 0.029504384240693782],
                uniform: false,
                argmax: Some(1),
            },
            open: OpenExpect {
                scores: [0.02330924008254431, 0.02330924008254431, 0.02330924008254431],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [-128, 127, -128],
        case: Case {
            label: "codes -128, 127, ...",
            logits: [-10.24, 10.16, -10.24],
            objectness: 1.0,
            ml: Expect {
                scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
                uniform: true,
                argmax: None,
            },
            map: Expect {
                scores: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333],
                uniform: true,
                argmax: None,
            },
            bayes: Expect {
                scores: [0.5579499999999992, 0.08339999999999992, 0.1586500000000004],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [1.10530649145026e-09, 0.7999999977893866, 1.10530649145026e-09],
                decision: 1,
            },
        },
    },
    QCase {
        codes: [53, -128, -128],
        case: Case {
            label: "only class 0 near its mean",
            logits: [4.24, -10.24, -10.24],
            objectness: 0.8,
            ml: Expect {
                scores: [0.7487778527460321, 0.025611079587448418, 0.025611079587448418],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.7972871443719872, 0.0013564337744708483, 0.0013564337744708483],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.7540388944069745, 0.0003954949411775564, 0.0007523413958971114],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.7551859536027301, 3.8857065942569626e-07, 3.8857065942569626e-07],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [-128, 29, -128],
        case: Case {
            label: "only class 1 near its mean",
            logits: [-10.24, 2.32, -10.24],
            objectness: 0.55,
            ml: Expect {
                scores: [0.015742132975273337, 0.5185157459703823, 0.015742132975273337],
                uniform: false,
                argmax: Some(1),
            },
            map: Expect {
                scores: [0.0011552583933369482, 0.547689495134255, 0.0011552583933369482],
                uniform: false,
                argmax: Some(1),
            },
            bayes: Expect {
                scores: [0.009711154034582257, 0.2982079261727867, 0.15940689137434783],
                uniform: false,
                argmax: Some(1),
            },
            open: OpenExpect {
                scores: [1.6401301222242615e-06, 0.46732269132147236, 1.6401301222242615e-06],
                decision: 1,
            },
        },
    },
    QCase {
        codes: [-128, -128, 36],
        case: Case {
            label: "only class 2 near its mean",
            logits: [-10.24, -10.24, 2.8799999],
            objectness: 1.0,
            ml: Expect {
                scores: [0.022742421532950075, 0.022742421532950075, 0.9545151569340998],
                uniform: false,
                argmax: Some(2),
            },
            map: Expect {
                scores: [0.0018093235414353723, 0.0018093235414353723, 0.9963813529171293],
                uniform: false,
                argmax: Some(2),
            },
            bayes: Expect {
                scores: [0.010950931395691643, 0.06346221191143002, 0.7842718473245902],
                uniform: false,
                argmax: Some(2),
            },
            open: OpenExpect {
                scores: [1.721427280102959e-06, 1.721427280102959e-06, 0.8586815477771517],
                decision: 2,
            },
        },
    },
    QCase {
        codes: [33, -47, -46],
        case: Case {
            label: "test.csv id 25001 as codes",
            logits: [2.6399999, -3.76, -3.6799998],
            objectness: 0.8,
            ml: Expect {
                scores: [0.554253912309447, 0.1495884743268369, 0.09615762528464504],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.7675105433302271, 0.01657893276991725, 0.015910535820784624],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.6487334489310251, 6.853860777003832e-05, 5.2853965488452225e-05],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.6466165772094187, 0.0010743906305099458, 0.0011638736643551457],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [-19, -27, 59],
        case: Case {
            label: "test.csv id 25002 as codes",
            logits: [-1.52, -2.1599998, 4.72],
            objectness: 0.55,
            ml: Expect {
                scores: [0.02885235193410888, 0.05086744620531667, 0.4702802137815034],
                uniform: false,
                argmax: Some(2),
            },
            map: Expect {
                scores: [0.006002207910078212, 0.00958912331794464, 0.5344086806929061],
                uniform: false,
                argmax: Some(2),
            },
            bayes: Expect {
                scores: [0.00018789394282847665, 0.001105127498358773, 0.46066940941672857],
                uniform: false,
                argmax: Some(2),
            },
            open: OpenExpect {
                scores: [0.0008980857037496524, 0.00047355385095481745, 0.4605907913032113],
                decision: 2,
            },
        },
    },
    QCase {
        codes: [-57, 53, 20],
        case: Case {
            label: "test.csv id 25003 as codes",
            logits: [-4.56, 4.24, 1.5999999],
            objectness: 1.0,
            ml: Expect {
                scores: [0.02721882826603401, 0.5494025710596986, 0.42337860067426747],
                uniform: false,
                argmax: Some(1),
            },
            map: Expect {
                scores: [0.00326504971033135, 0.47040401389942454, 0.526330936390244],
                uniform: false,
                argmax: Some(2),
            },
            bayes: Expect {
                scores: [4.4510956218419945e-06, 0.6982352764297374, 0.27656541869410073],
                uniform: false,
                argmax: Some(1),
            },
            open: OpenExpect {
                scores: [0.0001371290453805566, 0.9097472871217418, 0.06492073005233759],
                decision: 1,
            },
        },
    },
    QCase {
        codes: [-66, 34, -46],
        case: Case {
            label: "test.csv id 25004 as codes",
            logits: [-5.2799997, 2.72, -3.6799998],
            objectness: 0.8,
            ml: Expect {
                scores: [0.02030439705279854, 0.7396121303959147, 0.0400834844722157],
                uniform: false,
                argmax: Some(1),
            },
            map: Expect {
                scores: [0.001722660488480397, 0.7965446003421568, 0.0017327510902917706],
                uniform: false,
                argmax: Some(1),
            },
            bayes: Expect {
                scores: [0.0003167075792823076, 0.7371351407194957, 0.01550450546922828],
                uniform: false,
                argmax: Some(1),
            },
            open: OpenExpect {
                scores: [0.00025208535779639015, 0.7514556815784037, 0.0012485868318062392],
                decision: 1,
            },
        },
    },
    QCase {
        codes: [21, -62, -47],
        case: Case {
            label: "test.csv id 25005 as codes",
            logits: [1.68, -4.96, -3.76],
            objectness: 0.55,
            ml: Expect {
                scores: [0.29615448146027157, 0.10204229564746084, 0.15180323481319652],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.39747408329660905, 0.07609941672628882, 0.07642651189803111],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.31969499502482684, 9.494396402145536e-05, 9.220828087168799e-05],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.3180860708346997, 0.0004157471664131342, 0.0013803292686072413],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [19, -25, -55],
        case: Case {
            label: "test.csv id 25006 as codes",
            logits: [1.52, -2.0, -4.4],
            objectness: 1.0,
            ml: Expect {
                scores: [0.3903956512948776, 0.3167224459625911, 0.2928819027425314],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.4597159612723066, 0.313179880223428, 0.22710415850426552],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.43087237286286983, 0.0002187951453132807, 0.00012270999797231433],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.4177276916572987, 0.012364503962877589, 0.0011216823859791115],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [50, -54, -46],
        case: Case {
            label: "test.csv id 25007 as codes",
            logits: [4.0, -4.3199997, -3.6799998],
            objectness: 0.8,
            ml: Expect {
                scores: [0.6925135614334058, 0.05916408339839142, 0.04832236708913172],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.7971839052129512, 0.0014113347940711866, 0.001404771913906516],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.7844531107970681, 1.0083150349019376e-05, 1.5663497027596325e-05],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.7839257422399069, 0.00019096112694634202, 0.00036215407759147405],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [-30, -48, 50],
        case: Case {
            label: "test.csv id 25008 as codes",
            logits: [-2.3999999, -3.84, 4.0],
            objectness: 0.55,
            ml: Expect {
                scores: [0.017309943739402547, 0.05316005604062171, 0.4795300121409047],
                uniform: false,
                argmax: Some(2),
            },
            map: Expect {
                scores: [0.0017580381909270487, 0.0018109436557031753, 0.5464310300742987],
                uniform: false,
                argmax: Some(2),
            },
            bayes: Expect {
                scores: [7.34192355359262e-05, 0.0021411447237223214, 0.5123791029441452],
                uniform: false,
                argmax: Some(2),
            },
            open: OpenExpect {
                scores: [0.000853273302309737, 0.0002021641194916145, 0.513538229481602],
                decision: 2,
            },
        },
    },
    QCase {
        codes: [43, -44, -46],
        case: Case {
            label: "test.csv id 25009 as codes",
            logits: [3.4399998, -3.52, -3.6799998],
            objectness: 1.0,
            ml: Expect {
                scores: [0.8220443691363607, 0.10832363712322299, 0.06963199374041637],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.9940557660526074, 0.003075516715752079, 0.002868717231640579],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.9322811059657917, 3.3237583854635476e-05, 2.9200247439423692e-05],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.9307074867966117, 0.0008833314645244023, 0.0007527255359496897],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [53, -28, -34],
        case: Case {
            label: "test.csv id 25010 as codes",
            logits: [4.24, -2.24, -2.72],
            objectness: 0.8,
            ml: Expect {
                scores: [0.7130472986410831, 0.04299836556925691, 0.04395434771058902],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.7964786040635503, 0.0020708089433501974, 0.00145059891402848],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.7619929960207268, 1.0987944071117515e-05, 2.2148371045981435e-05],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.760138777850154, 0.0011659092309716527, 0.0007214452547182523],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [55, -36, -64],
        case: Case {
            label: "test.csv id 25011 as codes",
            logits: [4.4, -2.8799999, -5.12],
            objectness: 0.55,
            ml: Expect {
                scores: [0.4745318230095477, 0.04807674704268175, 0.027391441868699483],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.5478480965653993, 0.0011656330994048666, 0.0009862822561247605],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.5349382154680736, 6.407494474314696e-06, 1.556859163597611e-05],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.5345525656892655, 0.00036840592184816316, 3.9219943070384824e-05],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [73, -24, -38],
        case: Case {
            label: "test.csv id 25012 as codes",
            logits: [5.8399997, -1.92, -3.04],
            objectness: 1.0,
            ml: Expect {
                scores: [0.7611747126840754, 0.09666368976172762, 0.14216159755419694],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.9744250345541426, 0.014815824194072937, 0.010759141251784449],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.984101016097041, 4.8439304262151005e-05, 7.35917829900054e-05],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.983666684369931, 0.00041949128477312145, 0.0001368715295892747],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [56, -40, -43],
        case: Case {
            label: "test.csv id 25013 as codes",
            logits: [4.48, -3.1999998, -3.4399998],
            objectness: 0.8,
            ml: Expect {
                scores: [0.675381157843354, 0.06842560921857317, 0.05619324485900187],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.7968686088306637, 0.0016603389457595854, 0.001471064144505679],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.7881460479006732, 2.1530402103857107e-05, 2.919766514596056e-05],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.7875467527055446, 0.0003638268938219823, 0.0002861963685562927],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [-59, -83, 35],
        case: Case {
            label: "test.csv id 25014 as codes",
            logits: [-4.72, -6.64, 2.8],
            objectness: 0.55,
            ml: Expect {
                scores: [0.012477400534703344, 0.013837483474207957, 0.5236851279120176],
                uniform: false,
                argmax: Some(2),
            },
            map: Expect {
                scores: [0.001168773721440647, 0.0011687752424487082, 0.5476624629570396],
                uniform: false,
                argmax: Some(2),
            },
            bayes: Expect {
                scores: [0.00010282593533492285, 0.009129417300815526, 0.5102631044716452],
                uniform: false,
                argmax: Some(2),
            },
            open: OpenExpect {
                scores: [0.0002814604588002465, 4.126405967632068e-05, 0.519172623189319],
                decision: 2,
            },
        },
    },
    QCase {
        codes: [50, -47, -58],
        case: Case {
            label: "test.csv id 25015 as codes",
            logits: [4.0, -3.76, -4.64],
            objectness: 1.0,
            ml: Expect {
                scores: [0.8575028210718689, 0.09308289425511054, 0.049414284673020475],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.9964240860273847, 0.0018296300116761406, 0.0017462839609391153],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.979384952860657, 1.6129364698267863e-05, 1.813381322375907e-05],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.9788286461269369, 0.00041742792148536403, 0.0001731419901566275],
                decision: 0,
            },
        },
    },
    QCase {
        codes: [57, -49, -45],
        case: Case {
            label: "test.csv id 25016 as codes",
            logits: [4.56, -3.9199998, -3.6],
            objectness: 0.8,
            ml: Expect {
                scores: [0.695534180664099, 0.05750143506207614, 0.046964396194753844],
                uniform: false,
                argmax: Some(0),
            },
            map: Expect {
                scores: [0.7970088092748026, 0.001509100118244457, 0.0014821025278819917],
                uniform: false,
                argmax: Some(0),
            },
            bayes: Expect {
                scores: [0.7905063395831688, 1.5106784229658908e-05, 1.8633920816819705e-05],
                uniform: false,
                argmax: Some(0),
            },
            open: OpenExpect {
                scores: [0.7901501876419811, 0.00016401838687950794, 0.00022587425935463273],
                decision: 0,
            },
        },
    },
];

/// Inputs the layer must reject, and the error it must give.
pub static ERROR_CASES: &[ErrorCase<K>] = &[
    ErrorCase {
        label: "NaN logit in class 0",
        logits: [f32::NAN, 1.0, 1.0],
        objectness: 0.9,
        error: InferError::NanLogit { class: 0 },
    },
    ErrorCase {
        label: "NaN logit in class 1",
        logits: [1.0, f32::NAN, 1.0],
        objectness: 0.9,
        error: InferError::NanLogit { class: 1 },
    },
    ErrorCase {
        label: "NaN logit in class 2",
        logits: [1.0, 1.0, f32::NAN],
        objectness: 0.9,
        error: InferError::NanLogit { class: 2 },
    },
    ErrorCase {
        label: "NaN logits everywhere",
        logits: [f32::NAN, f32::NAN, f32::NAN],
        objectness: 1.0,
        error: InferError::NanLogit { class: 0 },
    },
    ErrorCase {
        label: "NaN logit and bad objectness",
        logits: [f32::NAN, f32::NAN, f32::NAN],
        objectness: 2.0,
        error: InferError::NanLogit { class: 0 },
    },
    ErrorCase {
        label: "objectness 1.5",
        logits: [0.0, 0.0, 0.0],
        objectness: 1.5,
        error: InferError::Objectness,
    },
    ErrorCase {
        label: "objectness -0.25",
        logits: [0.0, 0.0, 0.0],
        objectness: -0.25,
        error: InferError::Objectness,
    },
    ErrorCase {
        label: "objectness inf",
        logits: [0.0, 0.0, 0.0],
        objectness: f32::INFINITY,
        error: InferError::Objectness,
    },
    ErrorCase {
        label: "objectness nan",
        logits: [0.0, 0.0, 0.0],
        objectness: f32::NAN,
        error: InferError::Objectness,
    },
    ErrorCase {
        label: "objectness just above 1",
        logits: [0.0, 0.0, 0.0],
        objectness: 1.0000001,
        error: InferError::Objectness,
    },
];

/// CRC of `tests/golden/layer/small_maps.mlmap`, the small table with a recalibration
/// map on every head.
pub const MAPS_TABLE_CRC: u32 = 0x93d68882;

/// Detections and every head's scores after its map (ML, MAP, Bayes, open), from
/// `tests/golden/layer/maps.csv` (the numpy reference), or the error.
pub static MAP_CASES: &[MapCase<K>] = &[
    MapCase {
        label: "inside bins",
        logits: [0.5, 0.5, 0.5],
        objectness: 1.0,
        scores: [
            [0.2976190474078634, 0.5681818186949436, 0.02705627612078317],
            [0.11013359957055993, 0.801669332502813, 0.0032994484088974475],
            [0.25, 0.12499999999999976, 0.10483870782553319],
            [0.07425654903133248, 0.07425654903133248, 0.07425654903133248],
        ],
        error: None,
    },
    MapCase {
        label: "inside bins",
        logits: [2.5, -1.5, -3.5],
        objectness: 1.0,
        scores: [
            [0.285465410758003, 0.37755101816810177, 0.23942259333112803],
            [0.5650791983112399, 0.01158059313300886, 0.19473769690485848],
            [0.9127171556436968, 0.0029629720791934447, 0.0024850733128461973],
            [0.7161896474293002, 0.07283748429743317, 0.023228351361433162],
        ],
        error: None,
    },
    MapCase {
        label: "inside bins",
        logits: [3.25, 1.75, -0.5],
        objectness: 0.7,
        scores: [
            [0.301923070449191, 0.0810037504075906, 0.1914634076850955],
            [0.10000000149011612, 0.0013571461757475734, 0.0443719848830413],
            [0.054195801719673344, 0.20192308670444595, 0.25],
            [0.18868551102039316, 0.08007300724973374, 0.022136426806980088],
        ],
        error: None,
    },
    MapCase {
        label: "on inner edges",
        logits: [1.0, 0.0, -2.0],
        objectness: 1.0,
        scores: [
            [0.26131221684764333, 0.26131221684764333, 0.32352940681000536],
            [0.08843826902181579, 0.5751937029639145, 0.11618929578685233],
            [0.25, 0.08467742196094899, 0.10483870782553337],
            [0.15818162140785968, 0.08932802817758888, 0.028487293938653496],
        ],
        error: None,
    },
    MapCase {
        label: "on inner edges",
        logits: [3.0, -1.0, -3.0],
        objectness: 0.5,
        scores: [
            [0.11479591818067514, 0.08679691580701239, 0.0727974104480043],
            [0.10000000149011612, 0.030135662540213472, 0.0584287303033166],
            [0.2538573926865523, 0.009065126590325793, 0.007603009264037117],
            [0.18220793745055314, 0.01853080092760273, 0.005909593928277625],
        ],
        error: None,
    },
    MapCase {
        label: "on first edges",
        logits: [0.0, -2.0, -4.0],
        objectness: 1.0,
        scores: [
            [0.1375859912773197, 0.5128205142135167, 0.3252032480858932],
            [0.14178053919172046, 0.011088283340254823, 0.7196847016246064],
            [0.7691455725887, 0.009379823326171453, 0.007866948457180894],
            [0.31450095153059704, 0.10029641572773558, 0.03198518465166588],
        ],
        error: None,
    },
    MapCase {
        label: "on closed last edges",
        logits: [4.0, 2.0, 0.0],
        objectness: 1.0,
        scores: [
            [0.5128205142135167, 0.1375859912773197, 0.3252032480858932],
            [0.14577977469182538, 0.003983530372591832, 0.17353838943487507],
            [0.06705195603023553, 0.24982263388643808, 0.3093041984001841],
            [0.33683772230991865, 0.10741975839870369, 0.034256865339503256],
        ],
        error: None,
    },
    MapCase {
        label: "last edge and inner edge",
        logits: [4.0, 1.0, -1.0],
        objectness: 0.25,
        scores: [
            [0.09535256427668959, 0.025582395230352297, 0.06046747888714051],
            [0.05810312819989787, 0.07700406958288175, 0.10000000149011612],
            [0.048499103121185404, 0.18069828831542215, 0.223721679457968],
            [0.10129680635434234, 0.018242776069556908, 0.005817740912374507],
        ],
        error: None,
    },
    MapCase {
        label: "just below last edges",
        logits: [3.9999998, 1.9999999, -1e-45],
        objectness: 1.0,
        scores: [
            [0.5128205142135167, 0.1375859912773197, 0.3252032480858932],
            [0.14577965205155058, 0.003983525616057766, 0.1735381626869163],
            [0.06705195603023553, 0.24982263388643808, 0.3093041984001841],
            [0.336837701351097, 0.10741975903218819, 0.03425686787508946],
        ],
        error: None,
    },
    MapCase {
        label: "just below inner edges",
        logits: [0.99999994, -1e-45, -2.0000002],
        objectness: 1.0,
        scores: [
            [0.15393738197778603, 0.4338235424027477, 0.36385198926329293],
            [0.0728938464830028, 0.4740943530901375, 0.14305809645889786],
            [0.28134848660771133, 0.03774186960927384, 0.0316544707260483],
            [0.15415985886360054, 0.08705686895157293, 0.02776300258634099],
        ],
        error: None,
    },
    MapCase {
        label: "just above last edges",
        logits: [4.0000005, 2.0000002, 1e-45],
        objectness: 1.0,
        scores: [
            [0.24999999999999997, 0.24999999999999997, 0.24999999999999997],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.2749999999999996, 0.13750000000000004, 0.13750000000000004],
            [0.031530033400015034, 0.010055133034005341, 0.003206647422438102],
        ],
        error: None,
    },
    MapCase {
        label: "just below first edges",
        logits: [-1e-45, -2.0000002, -4.0000005],
        objectness: 0.8,
        scores: [
            [0.15000000596046445, 0.15000000596046445, 0.15000000596046445],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.1078431371098582, 0.25, 0.20098039479098254],
            [0.037451494183928076, 0.011943525449658883, 0.003808868064544812],
        ],
        error: None,
    },
    MapCase {
        label: "far outside",
        logits: [1e+30, -1e+30, 50.0],
        objectness: 1.0,
        scores: [
            [0.24999999999999997, 0.24999999999999997, 0.24999999999999997],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.2749999999999996, 0.13750000000000004, 0.13750000000000004],
            [0.031647817654295876, 0.0, 0.0],
        ],
        error: None,
    },
    MapCase {
        label: "far outside",
        logits: [-100.0, 100.0, 100.0],
        objectness: 0.6,
        scores: [
            [0.1125000019868215, 0.1125000019868215, 0.1125000019868215],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.25, 0.12500000000000022, 0.12500000000000022],
            [7.292062463080071e-52, 0.03136934530103112, 0.03136934530103112],
        ],
        error: None,
    },
    MapCase {
        label: "far outside one class",
        logits: [0.5, 0.5, 1e+30],
        objectness: 1.0,
        scores: [
            [0.2976190474078634, 0.5681818186949436, 0.02705627612078317],
            [0.11013359957055993, 0.801669332502813, 0.0032994484088974475],
            [0.25, 0.12499999999999976, 0.10483870782553319],
            [0.0, 0.0, 0.16026964709399746],
        ],
        error: None,
    },
    MapCase {
        label: "infinities",
        logits: [f32::INFINITY, f32::NEG_INFINITY, f32::INFINITY],
        objectness: 1.0,
        scores: [
            [0.24999999999999997, 0.24999999999999997, 0.24999999999999997],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.2749999999999996, 0.13750000000000004, 0.13750000000000004],
            [0.03144890882714794, 0.0, 0.03144890882714794],
        ],
        error: None,
    },
    MapCase {
        label: "infinities",
        logits: [f32::NEG_INFINITY, f32::INFINITY, f32::NEG_INFINITY],
        objectness: 0.9,
        scores: [
            [0.19999998807907107, 0.19999998807907107, 0.19999998807907107],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.25, 0.12500000000000022, 0.12500000000000022],
            [0.0, 0.031608035879381574, 0.0],
        ],
        error: None,
    },
    MapCase {
        label: "infinity and inside",
        logits: [f32::INFINITY, 0.5, -3.0],
        objectness: 1.0,
        scores: [
            [0.02003205079244296, 0.42067308156634337, 0.5208333317972978],
            [0.0020005141636925657, 0.4860663527712972, 0.213294014344949],
            [0.2294485052784839, 0.25, 0.07440166421133175],
            [0.1507569907322397, 0.0, 0.0],
        ],
        error: None,
    },
    MapCase {
        label: "subnormal logits",
        logits: [1e-40, -1e-40, 1e-40],
        objectness: 1.0,
        scores: [
            [0.21661664952068396, 0.6104651192004709, 0.01969242201678954],
            [0.03408595453110178, 0.9403129598596839, 0.0023511217755388687],
            [0.3937755125368848, 0.035783691928022686, 0.08457963329784746],
            [0.08332884953340831, 0.08332884953340831, 0.08332884953340831],
        ],
        error: None,
    },
    MapCase {
        label: "negative zero",
        logits: [-0.0, -0.0, -0.0],
        objectness: 1.0,
        scores: [
            [0.17871352795458129, 0.3411803720998699, 0.42241378812015273],
            [0.028260335627196247, 0.7796043914800712, 0.09628362581827486],
            [0.260391004709543, 0.08819695592250172, 0.2148699966858855],
            [0.147969855726321, 0.147969855726321, 0.147969855726321],
        ],
        error: None,
    },
    MapCase {
        label: "objectness 0",
        logits: [0.5, 0.5, 0.5],
        objectness: 0.0,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: None,
    },
    MapCase {
        label: "objectness -0",
        logits: [2.5, -1.5, -3.5],
        objectness: -0.0,
        scores: [
            [-0.0, -0.0, -0.0],
            [-0.0, -0.0, -0.0],
            [-0.0, -0.0, -0.0],
            [-0.0, -0.0, -0.0],
        ],
        error: None,
    },
    MapCase {
        label: "objectness 0 outside",
        logits: [1e+30, -1e+30, 50.0],
        objectness: 0.0,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: None,
    },
    MapCase {
        label: "objectness between",
        logits: [0.5, 0.5, 0.5],
        objectness: 0.93,
        scores: [
            [0.28595238193328953, 0.5459090936621112, 0.02599567020446796],
            [0.09665427592395115, 0.703552495928856, 0.002895626749274642],
            [0.25, 0.12499999999999974, 0.10483870782553319],
            [0.07124609090674602, 0.07124609090674602, 0.07124609090674602],
        ],
        error: None,
    },
    MapCase {
        label: "objectness between",
        logits: [2.5, -1.5, -3.5],
        objectness: 0.001,
        scores: [
            [0.04733518032088854, 0.0626045918413292, 0.03970047228534846],
            [0.10000000149011612, 0.0020493752628272595, 0.03446201884420044],
            [0.05152069570968199, 0.00016725267181019428, 0.00014027643194359027],
            [0.0316047219973486, 0.003214244230518378, 0.00102504356195305],
        ],
        error: None,
    },
    MapCase {
        label: "objectness 1",
        logits: [3.5, 1.5, -1.5],
        objectness: 1.0,
        scores: [
            [0.5128205142135167, 0.1375859912773197, 0.3252032480858932],
            [0.17901283522810657, 0.009908176683388158, 0.14288752681358521],
            [0.06709956078350705, 0.25, 0.1572989747082571],
            [0.20395665432585594, 0.0650431144743738, 0.011713764874993924],
        ],
        error: None,
    },
    MapCase {
        label: "objectness largest below 1",
        logits: [3.5, 1.5, -1.5],
        objectness: 0.99999994,
        scores: [
            [0.5128204985481932, 0.13758598707442807, 0.3252032381517857],
            [0.17901277091392706, 0.009908173123664338, 0.14288747547819333],
            [0.06709956078350705, 0.25, 0.15729897470825713],
            [0.20395664403173716, 0.06504311119151182, 0.011713764283775718],
        ],
        error: None,
    },
    MapCase {
        label: "objectness smallest subnormal",
        logits: [3.5, 1.5, -1.5],
        objectness: 1e-45,
        scores: [
            [0.0625, 0.016768292641374662, 0.03963414575280772],
            [0.10000000149011612, 0.0055348974381675105, 0.07981971167637297],
            [0.013419912356673684, 0.05000000074505806, 0.0314597954104389],
            [0.03125, 0.009965829916374076, 0.001794769352113042],
        ],
        error: None,
    },
    MapCase {
        label: "NaN logit",
        logits: [f32::NAN, 0.5, 0.5],
        objectness: 1.0,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::NanLogit { class: 0 }),
    },
    MapCase {
        label: "NaN logit",
        logits: [0.5, f32::NAN, 0.5],
        objectness: 1.0,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::NanLogit { class: 1 }),
    },
    MapCase {
        label: "NaN logit",
        logits: [0.5, 0.5, f32::NAN],
        objectness: 0.5,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::NanLogit { class: 2 }),
    },
    MapCase {
        label: "NaN logits",
        logits: [0.5, f32::NAN, f32::NAN],
        objectness: 0.5,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::NanLogit { class: 1 }),
    },
    MapCase {
        label: "objectness NaN",
        logits: [0.5, 0.5, 0.5],
        objectness: f32::NAN,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::Objectness),
    },
    MapCase {
        label: "objectness below 0",
        logits: [0.5, 0.5, 0.5],
        objectness: -0.1,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::Objectness),
    },
    MapCase {
        label: "objectness above 1",
        logits: [0.5, 0.5, 0.5],
        objectness: 1.1,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::Objectness),
    },
    MapCase {
        label: "objectness just above 1",
        logits: [0.5, 0.5, 0.5],
        objectness: 1.0000001,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::Objectness),
    },
    MapCase {
        label: "objectness just below 0",
        logits: [0.5, 0.5, 0.5],
        objectness: -1e-45,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::Objectness),
    },
    MapCase {
        label: "objectness +inf",
        logits: [0.5, 0.5, 0.5],
        objectness: f32::INFINITY,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::Objectness),
    },
    MapCase {
        label: "bayes inside bins",
        logits: [3.0, 0.5, -3.5],
        objectness: 1.0,
        scores: [
            [0.4488636395746788, 0.2299057664124741, 0.28464523062461716],
            [0.07510289417848798, 0.10000000149011612, 0.037593514530518894],
            [0.6861842275991972, 0.13482125107502768, 0.003647609023836055],
            [0.5067698705999422, 0.1214479247267408, 0.012351423037168472],
        ],
        error: None,
    },
    MapCase {
        label: "bayes inside bins",
        logits: [-3.0, -1.5, -0.5],
        objectness: 1.0,
        scores: [
            [0.01345050170891714, 0.5514705901084126, 0.34971305194789937],
            [0.013848362725691326, 0.07522220416438688, 0.847900413691288],
            [0.045859877143726885, 0.007956021483770895, 0.886997165551898],
            [0.05877618592990899, 0.1385012884982085, 0.24525738257839283],
        ],
        error: None,
    },
    MapCase {
        label: "bayes inside bins",
        logits: [1.0, 1.5, -2.5],
        objectness: 0.8,
        scores: [
            [0.23255968820472284, 0.12181697933935541, 0.2879310385119192],
            [0.061918263310379015, 0.005469441512946244, 0.11781018316232528],
            [0.008196720709561487, 0.25, 0.037810681129688155],
            [0.09349006510765569, 0.12440836997890434, 0.012652504441153945],
        ],
        error: None,
    },
    MapCase {
        label: "bayes inside zero-frequency bins",
        logits: [-3.0, 1.5, -3.5],
        objectness: 1.0,
        scores: [
            [0.02277327882309219, 0.2505060755377217, 0.5921052621259584],
            [0.009795647939793366, 0.05320847264367188, 0.8947465211362333],
            [0.0009499569965345784, 0.8981844559214163, 0.018230127250464627],
            [0.0481291330502798, 0.6297457974910327, 0.03616795062268454],
        ],
        error: None,
    },
    MapCase {
        label: "bayes on inner edges",
        logits: [0.0, 0.0, -2.0],
        objectness: 1.0,
        scores: [
            [0.17871352795458129, 0.3411803720998699, 0.42241378812015273],
            [0.02509001687353518, 0.6921463210823771, 0.13981375876270197],
            [0.25, 0.08467742196094899, 0.10483870782553337],
            [0.12675691758460306, 0.12675691758460306, 0.040423612203904016],
        ],
        error: None,
    },
    MapCase {
        label: "bayes on inner edges",
        logits: [-2.0, -1.0, -3.0],
        objectness: 0.9,
        scores: [
            [0.015211344836149965, 0.47155171825398723, 0.39549497423990065],
            [0.002628166609466642, 0.14452541527250146, 0.2802140653009849],
            [0.25, 0.22952960665222805, 0.15476189726507353],
            [0.08933018813425937, 0.15818544624822928, 0.050446376081778786],
        ],
        error: None,
    },
    MapCase {
        label: "bayes on inner edges",
        logits: [2.0, 1.0, -1.0],
        objectness: 1.0,
        scores: [
            [0.4338235424027477, 0.15393738197778603, 0.36385198926329293],
            [0.5074034431837553, 0.09294464385721651, 0.12070095222975272],
            [0.06705195603023553, 0.24982263388643808, 0.3093041984001841],
            [0.22997570115958216, 0.1298714460662569, 0.04141685575967569],
        ],
        error: None,
    },
    MapCase {
        label: "bayes on first edges",
        logits: [-4.0, -2.0, -4.0],
        objectness: 1.0,
        scores: [
            [0.01345050170891714, 0.5514705901084126, 0.34971305194789937],
            [0.012975925540260252, 0.01471249650233893, 0.9549141495148268],
            [0.25, 0.0945121930025727, 0.11701509043008768],
            [0.03674176961091876, 0.11521170940863898, 0.03674176961091876],
        ],
        error: None,
    },
    MapCase {
        label: "bayes on closed last edges",
        logits: [4.0, 2.0, 0.0],
        objectness: 1.0,
        scores: [
            [0.5128205142135167, 0.1375859912773197, 0.3252032480858932],
            [0.14577977469182538, 0.003983530372591832, 0.17353838943487507],
            [0.06705195603023553, 0.24982263388643808, 0.3093041984001841],
            [0.33683772230991865, 0.10741975839870369, 0.034256865339503256],
        ],
        error: None,
    },
    MapCase {
        label: "bayes just below inner edges",
        logits: [1.9999999, 0.99999994, -1.0000001],
        objectness: 1.0,
        scores: [
            [0.26131221684764333, 0.26131221684764333, 0.32352940681000536],
            [0.10000000149011612, 0.05458943665266644, 0.07089161207643686],
            [0.25, 0.08467742196094899, 0.10483870782553337],
            [0.15818162000860955, 0.08932803042990149, 0.028487293686659296],
        ],
        error: None,
    },
    MapCase {
        label: "bayes just above last edges",
        logits: [4.0000005, 2.0000002, 1e-45],
        objectness: 1.0,
        scores: [
            [0.24999999999999997, 0.24999999999999997, 0.24999999999999997],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.2749999999999996, 0.13750000000000004, 0.13750000000000004],
            [0.031530033400015034, 0.010055133034005341, 0.003206647422438102],
        ],
        error: None,
    },
    MapCase {
        label: "bayes just below first edges",
        logits: [-4.0000005, -2.0000002, -4.0000005],
        objectness: 1.0,
        scores: [
            [0.24999999999999997, 0.24999999999999997, 0.24999999999999997],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.2749999999999996, 0.13750000000000004, 0.13750000000000004],
            [0.01004328956251302, 0.03149289564654502, 0.01004328956251302],
        ],
        error: None,
    },
    MapCase {
        label: "bayes every logit outside",
        logits: [10.0, 10.0, 10.0],
        objectness: 1.0,
        scores: [
            [0.24999999999999997, 0.24999999999999997, 0.24999999999999997],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.2749999999999996, 0.13750000000000004, 0.13750000000000004],
            [0.03138260588476529, 0.03138260588476529, 0.03138260588476529],
        ],
        error: None,
    },
    MapCase {
        label: "bayes every logit outside",
        logits: [-10.0, 5.0, 1e+30],
        objectness: 0.7,
        scores: [
            [0.12083333233992258, 0.12083333233992258, 0.12083333233992258],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.25, 0.12500000000000022, 0.12500000000000022],
            [0.0, 0.0, 0.03152847235326475],
        ],
        error: None,
    },
    MapCase {
        label: "bayes every logit outside",
        logits: [f32::INFINITY, f32::NEG_INFINITY, f32::INFINITY],
        objectness: 1.0,
        scores: [
            [0.24999999999999997, 0.24999999999999997, 0.24999999999999997],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.2749999999999996, 0.13750000000000004, 0.13750000000000004],
            [0.03144890882714794, 0.0, 0.03144890882714794],
        ],
        error: None,
    },
    MapCase {
        label: "bayes every logit outside",
        logits: [f32::NEG_INFINITY, f32::INFINITY, f32::NEG_INFINITY],
        objectness: 0.3,
        scores: [
            [0.08750000099341075, 0.08750000099341075, 0.08750000099341075],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.24200000765919663, 0.12100000382959852, 0.12100000382959852],
            [0.0, 0.03136934530103112, 0.0],
        ],
        error: None,
    },
    MapCase {
        label: "bayes every logit outside at objectness 0",
        logits: [10.0, 10.0, 10.0],
        objectness: 0.0,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: None,
    },
    MapCase {
        label: "bayes one logit outside",
        logits: [10.0, 0.5, -3.5],
        objectness: 1.0,
        scores: [
            [0.02003205079244296, 0.42067308156634337, 0.5208333317972978],
            [0.002260445152784418, 0.5492219705285375, 0.2064718382187778],
            [0.2843707845989, 0.3098416181157472, 0.00838281111610528],
            [0.15447113443539043, 0.0006780297033014014, 6.895656484937437e-05],
        ],
        error: None,
    },
    MapCase {
        label: "bayes one logit outside",
        logits: [3.0, -1e+30, -3.5],
        objectness: 1.0,
        scores: [
            [0.5514705901084126, 0.01345050170891714, 0.34971305194789937],
            [0.4279857788890597, 0.0023454098430499355, 0.21423261744458702],
            [0.7844395933747734, 0.10440823201078084, 0.003368007297699629],
            [0.19633051026013443, 0.0, 0.004785132913397676],
        ],
        error: None,
    },
    MapCase {
        label: "bayes infinity and inside",
        logits: [f32::INFINITY, 0.5, -0.5],
        objectness: 1.0,
        scores: [
            [0.02003205079244296, 0.42067308156634337, 0.5208333317972978],
            [0.0027730615753525745, 0.673772748228837, 0.169787584533065],
            [0.23295036638227265, 0.11647518319113612, 0.28376288007330386],
            [0.2183798612628938, 0.0, 0.0],
        ],
        error: None,
    },
    MapCase {
        label: "bayes infinity and inside",
        logits: [-1.0, f32::NEG_INFINITY, -0.5],
        objectness: 0.6,
        scores: [
            [0.020329670334939307, 0.020329670334939307, 0.5285714400685108],
            [0.0042798080131116936, 0.0042798080131116936, 0.2620418786478268],
            [0.06817272869167282, 0.10705717708811639, 0.25],
            [0.07744393390415999, 0.0, 0.10305558746457208],
        ],
        error: None,
    },
    MapCase {
        label: "bayes objectness 0",
        logits: [3.0, 0.5, -3.5],
        objectness: 0.0,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: None,
    },
    MapCase {
        label: "bayes objectness between",
        logits: [3.0, 0.5, -3.5],
        objectness: 0.37,
        scores: [
            [0.10559659166251212, 0.054086059097410676, 0.06696369127922762],
            [0.07510289417848796, 0.10000000149011612, 0.037593514530518894],
            [0.25, 0.04911991767383544, 0.001328946687028282],
            [0.13989724993576752, 0.03352652094246085, 0.003409693858965086],
        ],
        error: None,
    },
    MapCase {
        label: "bayes objectness smallest subnormal",
        logits: [3.0, 0.5, -3.5],
        objectness: 1e-45,
        scores: [
            [0.0625, 0.032012195094249775, 0.03963414575280772],
            [0.07510289417848798, 0.10000000149011612, 0.037593514530518894],
            [0.05000000074505806, 0.00982398368115585, 0.0002657893413662262],
            [0.03125, 0.007489094888805497, 0.0007616513772899876],
        ],
        error: None,
    },
    MapCase {
        label: "bayes NaN logit",
        logits: [3.0, f32::NAN, -3.5],
        objectness: 1.0,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::NanLogit { class: 1 }),
    },
    MapCase {
        label: "bayes NaN logit and outside",
        logits: [10.0, 10.0, f32::NAN],
        objectness: 1.0,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::NanLogit { class: 2 }),
    },
    MapCase {
        label: "bayes objectness above 1",
        logits: [3.0, 0.5, -3.5],
        objectness: 1.5,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: Some(InferError::Objectness),
    },
    MapCase {
        label: "open tied logits",
        logits: [0.5, 0.5, -3.5],
        objectness: 1.0,
        scores: [
            [0.17871352795458129, 0.3411803720998699, 0.42241378812015273],
            [0.05791975665422732, 0.4216015170372381, 0.15849482520652527],
            [0.2926902017206681, 0.21603323747832176, 0.0058448114091147335],
            [0.17449545673343783, 0.17449545673343783, 0.017746430900552605],
        ],
        error: None,
    },
    MapCase {
        label: "open tied logits outside",
        logits: [50.0, 50.0, 50.0],
        objectness: 0.6,
        scores: [
            [0.1125000019868215, 0.1125000019868215, 0.1125000019868215],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.25, 0.12500000000000022, 0.12500000000000022],
            [0.03132956353402074, 0.03132956353402074, 0.03132956353402074],
        ],
        error: None,
    },
    MapCase {
        label: "open large logits",
        logits: [30.0, -20.0, 25.0],
        objectness: 1.0,
        scores: [
            [0.24999999999999997, 0.24999999999999997, 0.24999999999999997],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.2749999999999996, 0.13750000000000004, 0.13750000000000004],
            [0.0316262108781657, 1.2349045584153287e-14, 0.0018163761282430713],
        ],
        error: None,
    },
    MapCase {
        label: "open near-tied logits",
        logits: [1.0, 1.0000001, -1.0],
        objectness: 1.0,
        scores: [
            [0.3411803720998699, 0.17871352795458129, 0.42241378812015273],
            [0.08610844646616549, 0.07700403353220348, 0.10000000149011612],
            [0.01879118309279191, 0.2630081605699893, 0.3256291354080692],
            [0.18094428006494204, 0.18094429239079338, 0.057704317422975],
        ],
        error: None,
    },
    MapCase {
        label: "open every logit far outside",
        logits: [1e+06, -1e+06, 1e+06],
        objectness: 1.0,
        scores: [
            [0.24999999999999997, 0.24999999999999997, 0.24999999999999997],
            [0.10000000149011612, 0.10000000149011612, 0.10000000149011612],
            [0.2749999999999996, 0.13750000000000004, 0.13750000000000004],
            [0.03144890882714794, 0.0, 0.03144890882714794],
        ],
        error: None,
    },
    MapCase {
        label: "open inside every axis",
        logits: [1.0, 0.2, -1.5],
        objectness: 0.9,
        scores: [
            [0.2149886761437535, 0.2149886761437535, 0.2661764524549982],
            [0.0675457539391397, 0.40561949000063496, 0.0860444467279835],
            [0.25, 0.08467742196094899, 0.10483870782553335],
            [0.137684609971241, 0.0871667350312465, 0.03299625948168957],
        ],
        error: None,
    },
    MapCase {
        label: "maps objectness on a knot",
        logits: [3.5, -1.9, -3.9],
        objectness: 0.5,
        scores: [
            [0.10995370387337625, 0.10995370387337625, 0.06972673800605525],
            [0.10000000149011612, 0.00131645688183386, 0.07868263350576175],
            [0.3502171556436969, 0.0011369170037074509, 0.0009535432765885301],
            [0.2209668951465633, 0.010097608589447735, 0.0032201933731074587],
        ],
        error: None,
    },
    MapCase {
        label: "maps objectness between knots",
        logits: [3.5, -1.9, -3.9],
        objectness: 0.3,
        scores: [
            [0.0909722234554102, 0.0909722234554102, 0.05768970182221954],
            [0.10000000149011612, 0.00131645688183386, 0.07868263350576177],
            [0.25, 0.0008115800335493306, 0.0006806800161145188],
            [0.14508014161114124, 0.006629782633816123, 0.002114281011532577],
        ],
        error: None,
    },
    MapCase {
        label: "maps objectness quarter",
        logits: [0.5, 0.5, 0.5],
        objectness: 0.25,
        scores: [
            [0.05357142851863251, 0.10227272733686794, 0.00487012970039707],
            [0.013738033469216187, 0.10000000149011612, 0.00041157224360350377],
            [0.177647060456233, 0.08882353022811633, 0.07449715306894336],
            [0.042001637257833124, 0.042001637257833124, 0.042001637257833124],
        ],
        error: None,
    },
    MapCase {
        label: "maps objectness 0",
        logits: [3.5, -1.9, -3.9],
        objectness: 0.0,
        scores: [
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
        error: None,
    },
    MapCase {
        label: "maps objectness 1 inside",
        logits: [2.5, 0.5, -1.5],
        objectness: 1.0,
        scores: [
            [0.3461538577724166, 0.23449131723714037, 0.29032257918527166],
            [0.10000000149011612, 0.0916701186044945, 0.02955439453449404],
            [0.5378807144482483, 0.048497440977754866, 0.06004444782574613],
            [0.29649153230266456, 0.09455309384235153, 0.030153601641594634],
        ],
        error: None,
    },
];

/// The window of the monitor section of `tests/golden/monitor_small.mlmap`.
pub const MONITOR_WINDOW: u32 = 50;
/// Its thresholds of psi_max, oos_rate and q_mean, as stored.
pub const MONITOR_THRESHOLDS: (f32, f32, f32) = (0.55633014, 0.02, 0.776431);

/// The replayed stream, in order: (logits, objectness) of rows of test.csv and ood.csv
/// (test 0..50, ood 0..50, test 50..90, ood 50..60, test 90..110).
pub static MONITOR_ROWS: &[([f32; K], f32)] = &[
    ([2.6283, -3.7759, -3.7148], 0.6091),
    ([-1.5155, -2.1577, 4.7103], 0.7606),
    ([-4.5564, 4.2786, 1.5954], 0.9668),
    ([-5.2637, 2.7016, -3.642], 0.8178),
    ([1.6454, -4.9396, -3.7251], 0.8827),
    ([1.5308, -2.0375, -4.4045], 0.9384),
    ([3.9984, -4.2986, -3.707], 0.3099),
    ([-2.3733, -3.813, 3.9806], 0.8863),
    ([3.4216, -3.4924, -3.6607], 0.675),
    ([4.2784, -2.2393, -2.689], 0.7741),
    ([4.4131, -2.9186, -5.1224], 0.9002),
    ([5.836, -1.89, -3.0412], 0.8762),
    ([4.4407, -3.1612, -3.402], 0.7329),
    ([-4.7499, -6.611, 2.7963], 0.8177),
    ([4.0221, -3.7995, -4.6135], 0.9311),
    ([4.5637, -3.9038, -3.603], 0.8961),
    ([-1.8534, 0.2457, -4.9851], 0.916),
    ([-1.0234, -3.1679, -2.3721], 0.7391),
    ([2.6917, -2.4963, -3.2197], 0.9393),
    ([2.9695, -1.2599, -5.0518], 0.5308),
    ([-2.8216, 4.312, 2.8665], 0.8758),
    ([4.3198, -5.3174, -5.6301], 0.7797),
    ([4.9635, -4.9316, -2.4347], 0.9578),
    ([0.3371, -1.8213, -2.6587], 0.7074),
    ([-4.4915, -3.1762, 2.7763], 0.8233),
    ([-4.0812, 2.2384, 2.2394], 0.5927),
    ([-2.0458, 4.799, -2.9638], 0.8968),
    ([4.5754, -4.5664, -4.4227], 0.9039),
    ([-1.718, 2.7728, -2.1053], 0.535),
    ([4.437, -3.6941, -3.8221], 0.6084),
    ([-3.6613, -5.3458, 2.9296], 0.7326),
    ([-2.9979, 1.1177, 4.077], 0.7948),
    ([4.604, -2.6731, -2.8308], 0.8632),
    ([5.3057, -2.2218, -1.8596], 0.9464),
    ([4.9255, -3.4332, -3.3643], 0.8355),
    ([4.3574, -3.9951, -3.5811], 0.8723),
    ([4.7695, -4.1805, -3.1858], 0.8323),
    ([4.0472, -5.2421, -3.1861], 0.6725),
    ([2.7046, -5.5513, -4.7844], 0.8296),
    ([7.0379, -3.8244, -2.1448], 0.6423),
    ([-2.2876, -2.2363, 1.9912], 0.5222),
    ([4.8797, -3.3314, -2.791], 0.6163),
    ([-0.7567, 1.4919, 2.9424], 0.8476),
    ([-3.001, -0.1023, -3.9835], 0.812),
    ([-1.2776, 0.5756, 0.7222], 0.268),
    ([-4.1237, -1.1707, 3.7648], 0.377),
    ([2.3992, -2.5008, -3.4132], 0.625),
    ([4.6852, -1.5823, -2.3214], 0.8311),
    ([-4.1334, 1.6303, -5.235], 0.8264),
    ([4.6937, -2.7217, -3.2278], 0.9647),
    ([-10.4534, 10.7959, -7.7024], 0.8385),
    ([-10.2881, -7.1193, -9.6661], 0.859),
    ([-8.4535, -10.9736, 10.8759], 0.9815),
    ([-8.976, -10.285, -10.5834], 0.8034),
    ([-7.8824, 10.2017, -8.7984], 0.8105),
    ([-8.9886, 10.691, -9.4215], 0.7918),
    ([10.0064, -6.6502, -8.1966], 0.7864),
    ([-8.8381, -10.4374, -7.9937], 0.7197),
    ([-7.7261, -10.7428, -8.6118], 0.9392),
    ([-9.0956, -9.1616, -10.257], 0.8798),
    ([-11.6127, -11.6128, -7.2562], 0.6048),
    ([-7.168, -10.6076, -8.222], 0.6937),
    ([-9.9469, -10.4345, 12.2256], 0.7881),
    ([-7.7579, -8.8853, -8.431], 0.6822),
    ([-8.6312, -9.3509, 10.9118], 0.9133),
    ([-8.037, -6.3155, -9.4015], 0.8498),
    ([-10.7214, 9.8345, -9.5733], 0.8854),
    ([-10.3824, -8.7161, -10.7215], 0.9085),
    ([-8.8727, -8.2316, 11.5453], 0.4989),
    ([11.9258, -8.8794, -7.1145], 0.6617),
    ([10.6673, -8.5437, -10.8514], 0.9467),
    ([11.6742, -8.8753, -9.4693], 0.7894),
    ([-8.4274, -10.8336, 11.2306], 0.636),
    ([10.4376, -9.832, -9.8274], 0.7861),
    ([-10.6282, 9.8854, -9.6723], 0.661),
    ([-8.7172, -11.1047, -7.4119], 0.8745),
    ([-9.9454, -5.0007, -9.024], 0.7754),
    ([11.2221, -10.7095, -6.869], 0.7842),
    ([-8.002, -9.0933, -8.762], 0.5353),
    ([-10.2522, -10.6386, -9.8185], 0.8146),
    ([10.4576, -11.3072, -7.9608], 0.8223),
    ([-11.0321, -10.6926, -6.4035], 0.7193),
    ([9.4982, -9.2897, -7.8259], 0.6042),
    ([-10.4412, 11.2029, -7.9742], 0.8599),
    ([-7.5636, 10.905, -6.7894], 0.7012),
    ([-7.969, -7.6826, -7.8865], 0.7904),
    ([-7.3541, -8.7549, -9.6313], 0.7735),
    ([-8.3525, -9.4563, 12.016], 0.8223),
    ([-12.5964, -11.0153, -7.1614], 0.9704),
    ([-8.6452, -8.687, -5.8171], 0.9911),
    ([-7.251, 13.3675, -7.9085], 0.7731),
    ([-9.5177, -9.9777, -10.7237], 0.6494),
    ([-8.7204, -8.9335, -7.5244], 0.6451),
    ([11.0239, -8.5494, -9.0203], 0.6568),
    ([-7.0521, -6.0413, -7.0633], 0.9559),
    ([10.8326, -7.7852, -8.0404], 0.8078),
    ([-10.3607, -9.267, -11.118], 0.7399),
    ([-11.1116, -9.337, 8.766], 0.5929),
    ([-5.8212, -9.9106, -11.065], 0.8877),
    ([-8.4628, -7.9505, -7.334], 0.4449),
    ([4.9884, -4.541, -2.3709], 0.9006),
    ([5.6766, -4.5858, -3.0265], 0.6035),
    ([5.7682, -3.4718, -5.2742], 0.9579),
    ([5.9888, -2.2258, -1.1148], 0.8348),
    ([4.4195, -2.4176, -0.1086], 0.5724),
    ([5.5553, -2.0842, -2.7159], 0.8565),
    ([3.1029, -2.441, -3.3745], 0.6258),
    ([-4.2253, 2.3148, -5.5251], 0.8838),
    ([-3.1097, -4.6546, 4.0589], 0.6846),
    ([5.2134, -2.2377, -3.6585], 0.7378),
    ([1.4942, -4.5502, -1.0935], 0.708),
    ([4.2831, -2.2424, -5.1282], 0.8339),
    ([3.6786, -6.1019, -1.7318], 0.887),
    ([-3.8476, 2.6811, -3.0971], 0.7),
    ([3.3066, -2.8151, -5.2044], 0.6845),
    ([-2.8208, 3.7709, -3.7105], 0.7708),
    ([4.0973, -3.9646, -5.6248], 0.936),
    ([-3.162, -3.3519, 2.0272], 0.3425),
    ([-1.9, 1.9534, -3.4998], 0.922),
    ([-3.3553, -0.642, 1.4073], 0.6864),
    ([4.6722, -3.4427, -3.7744], 0.5841),
    ([-1.9922, 4.7002, -4.1188], 0.9002),
    ([-1.193, -5.4795, 4.0184], 0.6411),
    ([4.2391, -4.2002, -3.6146], 0.9116),
    ([1.9053, -2.598, -2.6251], 0.2851),
    ([5.6697, -2.3938, -4.1679], 0.959),
    ([3.7754, -3.2996, -5.1847], 0.8824),
    ([5.2753, -2.6854, -3.7024], 0.8403),
    ([6.3575, -3.9077, -3.3902], 0.7632),
    ([2.4296, -4.6918, -2.6394], 0.5798),
    ([6.1584, -4.2748, -2.2762], 0.7631),
    ([3.6539, -2.3346, -3.7151], 0.9317),
    ([-4.1242, 2.7747, -2.6174], 0.7045),
    ([-2.2198, -3.5434, -0.7555], 0.8581),
    ([-3.3574, 1.923, -4.8615], 0.8144),
    ([4.1582, -4.843, -6.3177], 0.7921),
    ([-0.8326, 4.378, 0.8501], 0.6445),
    ([3.2715, -2.9484, -4.4099], 0.8191),
    ([-3.6587, 3.244, -0.3543], 0.7815),
    ([-3.6747, 1.5035, -2.614], 0.6812),
    ([-9.0903, -10.1245, -10.9508], 0.6287),
    ([9.016, -9.8941, -9.493], 0.8269),
    ([10.1271, -7.7065, -9.2502], 0.7324),
    ([9.0656, -9.3193, -8.9411], 0.6318),
    ([-8.4711, 11.8286, -6.0396], 0.6298),
    ([-8.605, -9.6672, -8.4954], 0.8087),
    ([-6.4135, -7.3752, -9.2564], 0.9172),
    ([11.6823, -10.1531, -9.1303], 0.7495),
    ([-11.9277, -6.8819, -9.8262], 0.9272),
    ([-9.3076, 9.1553, -7.6881], 0.718),
    ([4.3615, -5.9339, -4.1546], 0.8495),
    ([4.4256, -3.5018, -3.1032], 0.91),
    ([-5.6255, -3.0138, 2.2257], 0.9023),
    ([5.1638, -3.0861, -2.5825], 0.9537),
    ([3.8792, -4.2125, -4.9604], 0.814),
    ([-2.7434, -4.0672, -0.1131], 0.8258),
    ([4.9046, -4.3751, -3.7482], 0.8015),
    ([5.6056, -2.6616, -1.7671], 0.8072),
    ([4.4302, -3.2738, -3.77], 0.9258),
    ([6.1467, -2.4189, -0.1684], 0.9596),
    ([-4.4737, -3.6843, 4.935], 0.6103),
    ([1.5972, -1.8577, -1.4658], 0.543),
    ([-4.0966, -2.7068, 3.6626], 0.9078),
    ([-2.4469, -2.7075, 2.8245], 0.6994),
    ([2.9255, -5.7974, -4.8343], 0.6892),
    ([2.2467, -4.0703, -3.3704], 0.9014),
    ([-4.0303, -2.2113, 2.8589], 0.7602),
    ([5.9604, -4.6606, -3.0797], 0.9079),
    ([5.0899, -2.484, -2.3025], 0.8083),
    ([3.5671, -4.4639, -2.5717], 0.8491),
];

/// Each window's metrics (numpy reference, float64) and alarms; the last is partial.
pub static MONITOR_WINDOWS: &[WindowCase<K>] = &[
    WindowCase {
        window: 0,
        rows: 50,
        psi: [0.23583202880024878, 0.1638990115861952, 0.24439594027539627],
        psi_max: 0.24439594027539627,
        psi_logit: Some(2),
        oos_rate: 0.0,
        q_mean: 0.851042078054535,
        alarms: (false, false, false),
    },
    WindowCase {
        window: 1,
        rows: 50,
        psi: [4.786711885498603, 5.100059206227654, 4.683409451743263],
        psi_max: 5.100059206227654,
        psi_logit: Some(1),
        oos_rate: 0.94,
        q_mean: 0.7897918962688751,
        alarms: (true, true, false),
    },
    WindowCase {
        window: 2,
        rows: 50,
        psi: [0.5085417000137727, 0.6791191400672094, 0.7697304639089436],
        psi_max: 0.7697304639089436,
        psi_logit: Some(2),
        oos_rate: 0.2,
        q_mean: 0.8627852156186674,
        alarms: (true, true, false),
    },
    WindowCase {
        window: 3,
        rows: 20,
        psi: [0.21689948160901446, 0.3192828935781301, 0.27222882706408064],
        psi_max: 0.3192828935781301,
        psi_logit: Some(1),
        oos_rate: 0.0,
        q_mean: 0.8730041991250136,
        alarms: (false, false, false),
    },
];

/// The alpha of the conformal section of `tests/golden/conformal_small.mlmap` (open
/// head).
pub const CONFORMAL_ALPHA: f32 = 0.1;
/// Its thresholds, from the numpy reference.
pub const CONFORMAL_THRESHOLDS: [f64; K] = [0.5950135554273936, 0.2568895416875959, 0.2695576753029198];

/// Detections and their sets (`tests/golden/conformal/sets_open_0.1.csv`).
pub static SET_CASES: &[SetCase<K>] = &[
    SetCase {
        label: "test.csv id 25001",
        logits: [2.6283, -3.7759, -3.7148],
        objectness: 0.6091,
        mask: 0,
        compared: true,
    },
    SetCase {
        label: "test.csv id 25002",
        logits: [-1.5155, -2.1577, 4.7103],
        objectness: 0.7606,
        mask: 4,
        compared: true,
    },
    SetCase {
        label: "test.csv id 25003",
        logits: [-4.5564, 4.2786, 1.5954],
        objectness: 0.9668,
        mask: 2,
        compared: true,
    },
    SetCase {
        label: "test.csv id 25004",
        logits: [-5.2637, 2.7016, -3.642],
        objectness: 0.8178,
        mask: 2,
        compared: true,
    },
    SetCase {
        label: "test.csv id 25005",
        logits: [1.6454, -4.9396, -3.7251],
        objectness: 0.8827,
        mask: 0,
        compared: true,
    },
    SetCase {
        label: "test.csv id 25006",
        logits: [1.5308, -2.0375, -4.4045],
        objectness: 0.9384,
        mask: 0,
        compared: true,
    },
    SetCase {
        label: "test.csv id 25007",
        logits: [3.9984, -4.2986, -3.707],
        objectness: 0.3099,
        mask: 0,
        compared: true,
    },
    SetCase {
        label: "test.csv id 25008",
        logits: [-2.3733, -3.813, 3.9806],
        objectness: 0.8863,
        mask: 4,
        compared: true,
    },
    SetCase {
        label: "test.csv id 25009",
        logits: [3.4216, -3.4924, -3.6607],
        objectness: 0.675,
        mask: 1,
        compared: true,
    },
    SetCase {
        label: "test.csv id 25010",
        logits: [4.2784, -2.2393, -2.689],
        objectness: 0.7741,
        mask: 1,
        compared: true,
    },
    SetCase {
        label: "test.csv id 25011",
        logits: [4.4131, -2.9186, -5.1224],
        objectness: 0.9002,
        mask: 1,
        compared: true,
    },
    SetCase {
        label: "test.csv id 25012",
        logits: [5.836, -1.89, -3.0412],
        objectness: 0.8762,
        mask: 1,
        compared: true,
    },
];
